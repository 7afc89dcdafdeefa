package robotmiddleware

import java.io.File
import java.nio.file.{Files, Paths}

import scala.io.Source
import scala.reflect.internal.util.BatchSourceFile
import scala.tools.nsc.reporters.StoreReporter
import scala.tools.nsc.{Global, Settings}
import scala.util.Using

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.testkit.TempFiles.withTempDir

/** The middleware's layer, as the compiler keeps it: its main code is compiled against the api and the gateway's access
  * protocol (`access`), never the gateway, so main code that names a gateway internal does not build. The build writes
  * that main classpath for this spec (this JVM's own holds the gateway, which the middleware's specs drive); scalac
  * shows here that a probe naming a gateway internal is refused against it and one that speaks the access protocol is
  * not.
  */
class MiddlewareLayerSpec extends AnyWordSpec with Matchers {

  /** The middleware's main classpath, as the build compiles it. */
  private val mainClasspath: Seq[String] =
    Using.resource(Source.fromResource("robotmiddleware-main-classpath.txt"))(_.getLines().filter(_.nonEmpty).toVector)

  /** The errors scalac reports (typer only, nothing written) for `source` against the middleware's main classpath. */
  private def compileErrors(source: String): Vector[String] = withTempDir("middleware-probe") { out =>
    val settings = new Settings()
    settings.processArgumentString(s"-Ystop-after:typer -d $out")
    settings.classpath.value = mainClasspath.mkString(File.pathSeparator)
    val reporter = new StoreReporter(settings)
    val global = new Global(settings, reporter)
    new global.Run().compileSources(List(new BatchSourceFile("Probe.scala", source)))
    reporter.infos.toVector.filter(_.severity == reporter.ERROR).map(_.msg)
  }

  /** Whether `entry` (a classes directory or a jar) holds `path`. */
  private def holds(entry: String, path: String): Boolean = {
    val f = new File(entry)
    if (f.isDirectory) Files.exists(Paths.get(entry, path))
    else f.isFile && Using.resource(new java.util.zip.ZipFile(f))(_.getEntry(path) != null)
  }

  "The middleware's main classpath" should {
    "hold the api and the access protocol but none of the gateway's or the simulator's classes" in {
      mainClasspath.exists(holds(_, "naogateway/api/RobotSnapshot.class")) shouldBe true
      mainClasspath.exists(holds(_, "naogateway/access/GatewayAccess$.class")) shouldBe true
      mainClasspath.exists(holds(_, "robotmiddleware/RobotMiddleware$.class")) shouldBe true
      mainClasspath.filter(e =>
        Seq("naogateway/gateway/Gateway$.class", "naogateway/gateway/robot/RobotActor$.class",
          "naogateway/sim/Fleet$.class").exists(
          holds(e, _))) shouldBe empty
    }
  }

  "A probe against the middleware's main classpath" should {
    "compile when it speaks the access protocol, as the middleware does" in {
      compileErrors(
        """package probe
          |import akka.actor.typed.ActorRef
          |import naogateway.access.{GatewayAccess, RobotAccess}
          |import naogateway.api.{CallResult, RobotSnapshot}
          |import naogateway.wire.RpcCall
          |object Probe {
          |  def ask(g: ActorRef[GatewayAccess.Command], r: ActorRef[Option[ActorRef[RobotAccess.Command]]]): Unit =
          |    g ! GatewayAccess.GetRobotAccess(1, r)
          |  def snapshot(robot: ActorRef[RobotAccess.Command], s: ActorRef[RobotSnapshot]): Unit =
          |    robot ! RobotAccess.GetSnapshot(s)
          |  def call(o: RobotAccess.Opened, c: RpcCall, a: ActorRef[CallResult]): Unit = o.response ! RobotAccess.Call(c, a)
          |}
          |""".stripMargin) shouldBe empty
    }

    "be refused when it names a gateway internal" in {
      val probes = Seq(
        "Gateway" -> "object Probe { val g = naogateway.gateway.Gateway }",
        "RobotActor" -> "object Probe { def c(r: akka.actor.typed.ActorRef[naogateway.gateway.robot.RobotActor.Command]) = r }",
        "ResponseActor" -> "import naogateway.gateway.robot.ResponseActor\nobject Probe { val r = ResponseActor }",
        "NoResponseActor" -> "object Probe { val s = naogateway.gateway.robot.NoResponseActor }",
        "GatewaySettings" ->
          "object Probe { def s(system: akka.actor.typed.ActorSystem[_]) = naogateway.gateway.GatewaySettings(system) }"
      )
      probes.foreach { case (name, text) =>
        val errors = compileErrors(s"package probe\n$text\n")
        withClue(text)(errors should not be empty)
        // The gateway's package is not on that classpath at all, or the name is not in the package scalac sees.
        errors.mkString("\n") should (include(name) or include("object gateway is not a member of package naogateway"))
      }
    }
  }
}
