package apps

import java.nio.charset.StandardCharsets
import java.nio.file.{Files, Path, Paths}

import scala.reflect.internal.util.BatchSourceFile
import scala.reflect.runtime.universe._
import scala.tools.nsc.reporters.StoreReporter
import scala.tools.nsc.{Global, Settings}

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.api.{RobotFailure, RobotSnapshot, VisionFrame}
import naogateway.wire.HaViMoRegion
import naogateway.testkit.TempFiles.withTempDir

/** docs/writing-apps.md is the API a team reads: its first app is the template's, as compiled; its tables name the
  * fields and types the code has; its other complete examples compile against the libraries an app gets.
  */
class WritingAppsDocSpec extends AnyWordSpec with Matchers {
  private def find(relative: String): Path =
    Seq(Paths.get("..", relative), Paths.get(relative)).find(Files.exists(_)).getOrElse(fail(s"$relative not found"))

  private def read(relative: String): String = new String(Files.readAllBytes(find(relative)), StandardCharsets.UTF_8)

  private lazy val doc = read("docs/writing-apps.md")

  /** The rows (cells without backticks) of the first table after `marker`. */
  private def tableAfter(marker: String): Vector[Vector[String]] = {
    val at = doc.indexOf(marker)
    withClue(s"docs/writing-apps.md has no '$marker': ")(at should be >= 0)
    doc.substring(at).linesIterator.dropWhile(!_.startsWith("|")).takeWhile(_.startsWith("|")).toVector.drop(2).map(
      _.split("\\|", -1).toVector.drop(1).dropRight(1).map(_.trim.replace("`", "")))
  }

  /** The (field, type) rows of the table after `marker`. */
  private def fieldTable(marker: String): Vector[(String, String)] = tableAfter(marker).map(r => r(0) -> r(1))

  /** A case class's fields and their types as the docs write them (no package prefixes). */
  private def fields(tpe: Type): Vector[(String, String)] =
    tpe.decl(termNames.CONSTRUCTOR).asMethod.paramLists.head.toVector.map(p =>
      p.name.decodedName.toString -> p.typeSignature.toString.replaceAll("\\b[a-z]\\w*\\.", ""))

  "docs/writing-apps.md" should {
    "show the template's build and first app exactly as they are, the app in under 40 lines of code" in {
      val build = read("examples/first-app/build.sbt")
      val source = read("examples/first-app/src/main/scala/firstapp/HelloRobot.scala")
      doc should include(build)
      doc should include(source)
      source.linesIterator.count(l =>
        l.trim.nonEmpty && !l.trim.startsWith("import") && !l.trim.startsWith("/**") && !l.trim.startsWith("*") &&
          !l.trim.startsWith("//")) should be < 40
    }

    "name every field of RobotSnapshot with its type, in order" in {
      fieldTable("### `RobotSnapshot`") shouldBe fields(typeOf[RobotSnapshot])
      fields(typeOf[RobotSnapshot]).take(1) shouldBe Vector("robotId" -> "Int")
      fields(typeOf[RobotSnapshot]) should contain allOf ("batteryVoltage" -> "Option[Double]",
        "posture" -> "Option[Posture]")
    }

    "name the camera's frame types, their fields and the region's fields with their types" in {
      fieldTable("`VisionFrame.Regions`, the regions") shouldBe fields(typeOf[VisionFrame.Regions])
      fieldTable("`VisionFrame.Grid`, the 32") shouldBe fields(typeOf[VisionFrame.Grid])
      fieldTable("`naogateway.wire.HaViMoRegion`, one region") shouldBe fields(typeOf[HaViMoRegion])
      typeOf[VisionFrame].typeSymbol.asClass.knownDirectSubclasses.map(_.name.toString) shouldBe Set("Regions", "Grid")
    }

    "list every RobotFailure with its fields" in {
      val documented = tableAfter("| failure | meaning |").map(_.head).toSet
      val failures = typeOf[RobotFailure].typeSymbol.asClass.knownDirectSubclasses.map { c =>
        s"${c.name}(${fields(c.asType.toType).map(_._1).mkString(", ")})"
      }
      failures should have size 10
      documented shouldBe failures
    }

    "give the ball's colour class as the demo's simulated camera has it" in {
      doc should include("in the demo 1 is the ball, 2 the yellow goal, 3 the blue goal")
      naogateway.sim.Scene.BallColour shouldBe 1
      naogateway.sim.Scene.YellowGoalColour shouldBe 2
      naogateway.sim.Scene.BlueGoalColour shouldBe 3
      doc should include("val BallColour = 1")
    }

    "hold complete examples that compile against an app's libraries" in {
      val blocks = "(?s)```scala\n(.*?)```".r.findAllMatchIn(doc).map(_.group(1)).toVector
      val examples = blocks.filter(b => b.contains("object ") && !b.contains("package firstapp"))
      examples should not be empty
      val errors = withTempDir("writing-apps") { out =>
        val settings = new Settings()
        settings.processArgumentString(s"-Ystop-after:refchecks -d $out")
        settings.classpath.value = System.getProperty("java.class.path")
        val reporter = new StoreReporter(settings)
        val global = new Global(settings, reporter)
        new global.Run().compileSources(examples.zipWithIndex.map { case (text, i) =>
          new BatchSourceFile(s"example$i.scala", text)
        }.toList)
        reporter.infos.toVector.filter(_.severity == reporter.ERROR).map(i =>
          s"${i.pos.source.file.name}:${i.pos.line}: ${i.msg}")
      }
      errors shouldBe empty
    }
  }

  "The template examples/first-app" should {
    "run sbt as the clone does, from the same caches and repositories" in {
      read("examples/first-app/sbt") shouldBe read("sbt")
      read("examples/first-app/project/repositories") shouldBe read("project/repositories")
      read("examples/first-app/project/build.properties") shouldBe read("project/build.properties")
      find("examples/first-app/sbt").toFile.canExecute shouldBe true
    }

    "use the Scala and Akka versions the libraries are built with" in {
      val build = read("examples/first-app/build.sbt")
      build should include(s"""scalaVersion := "${scala.util.Properties.versionNumberString}"""")
      build should include(s""""akka-slf4j" % "${akka.Version.current}"""")
    }
  }
}
