package naogateway.api

import java.nio.file.Files

import scala.reflect.internal.util.BatchSourceFile
import scala.tools.nsc.reporters.StoreReporter
import scala.tools.nsc.{Global, Settings}

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** The compiler holds the api's boundary: a source written against the api's classpath (this spec's JVM's, which is the
  * api module's test classpath) compiles when it uses the api's data and fails when it imports a gateway internal. The
  * same probe, run against the apps module's classpath, is how the build will show apps' boundary (issue 22).
  */
class ApiBoundarySpec extends AnyWordSpec with Matchers {

  /** The errors scalac reports for `source` (typer only, nothing written), against this JVM's class path. */
  private def compileErrors(source: String): Vector[String] = {
    val out = Files.createTempDirectory("api-probe")
    val settings = new Settings()
    settings.processArgumentString(s"-usejavacp -Ystop-after:typer -d $out")
    val reporter = new StoreReporter(settings)
    val global = new Global(settings, reporter)
    try new global.Run().compileSources(List(new BatchSourceFile("Probe.scala", source)))
    finally Files.deleteIfExists(out) // typer writes nothing into it: an empty directory per probe, not one per run
    reporter.infos.toVector.filter(_.severity == reporter.ERROR).map(_.msg)
  }

  "A probe source against the api's classpath" should {
    "compile when it uses what apps may see" in {
      compileErrors(
        """package probe
          |import naogateway.api.{RobotFailure, RobotSnapshot, TrafficStats}
          |import naogateway.wire.Posture
          |object Probe {
          |  def describe(s: RobotSnapshot, t: TrafficStats, f: RobotFailure, p: Posture): String = s"${s.robotId} ${t.teamLoad} ${f.describe} $p"
          |}
          |""".stripMargin) shouldBe empty
    }

    "fail when it imports a gateway internal" in {
      val errors = compileErrors(
        """package probe
          |import naogateway.gateway.Gateway
          |object Probe { val g: Gateway.type = Gateway }
          |""".stripMargin)
      errors should not be empty
      errors.head should include("gateway")
    }

    "fail when it reaches for Akka" in {
      compileErrors(
        """package probe
          |object Probe { val r: Option[akka.actor.typed.ActorRef[Int]] = None }
          |""".stripMargin) should not be empty
    }
  }
}
