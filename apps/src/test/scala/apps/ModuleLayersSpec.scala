package apps

import java.io.File
import java.net.URL
import java.nio.file.{Files, Path, Paths}
import java.util.zip.ZipFile

import scala.jdk.CollectionConverters._
import scala.reflect.internal.util.BatchSourceFile
import scala.tools.nsc.reporters.StoreReporter
import scala.tools.nsc.{Global, Settings}
import scala.util.Using

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.testkit.TempFiles.withTempDir

/** The modules the build separates stay separate in what it produces: the gateway ships no simulator class, the data
  * apps see is a module of its own (api), the gateway's integration specs are not the simulator's tests, and every app
  * compiles without the gateway's and the simulator's classes (the build compiles apps so; scalac shows it here).
  */
class ModuleLayersSpec extends AnyWordSpec with Matchers {

  /** Where a class was loaded from: a classes directory or a jar. */
  private def origin(cls: Class[_]): Path = {
    val location: URL = cls.getProtectionDomain.getCodeSource.getLocation
    Paths.get(location.toURI)
  }

  /** The class-file paths ('/'-separated) of a classes directory or a jar. */
  private def classEntries(at: Path): Seq[String] =
    if (Files.isDirectory(at))
      Using.resource(Files.walk(at))(_.iterator.asScala.filter(p => Files.isRegularFile(p)).map(p =>
          at.relativize(p).toString.replace(File.separatorChar, '/')).toVector)
    else
      Using.resource(new ZipFile(at.toFile))(_.entries.asScala.map(_.getName).toVector)

  /** A Scala object's class, without running its initialiser. */
  private def objectClass(name: String): Class[_] = Class.forName(name + "$", false, getClass.getClassLoader)

  private val gateway = origin(objectClass("naogateway.gateway.Gateway"))

  "The gateway's classes" should {
    "hold no naogateway.sim class" in {
      val entries = classEntries(gateway)
      entries should contain("naogateway/gateway/Gateway.class")
      entries.filter(_.startsWith("naogateway/sim/")) shouldBe empty
    }

    "hold no wire class either: the wire format is a module of its own" in {
      classEntries(gateway).filter(_.startsWith("naogateway/wire/")) shouldBe empty
      origin(objectClass("naogateway.wire.Datagram")) should not be gateway
    }
  }

  "The simulator's classes" should {
    "come from the sim module, not the gateway's" in {
      val sim = origin(classOf[naogateway.sim.FleetSettings])
      sim should not be gateway
      classEntries(sim) should contain("naogateway/sim/SimulatedRobot.class")
    }

    "keep the test-only experiments out of the simulator's main classes" in {
      val sim = origin(classOf[naogateway.sim.FleetSettings])
      origin(objectClass("naogateway.sim.StreamPairSimulation")) should not be sim
      classEntries(sim).filter(e =>
        e.contains("StreamPairSimulation") || e.contains("OverflowExperiment")) shouldBe empty
    }
  }

  "The api's classes" should {
    "come from the api module, not the gateway's, and hold no actor" in {
      val api = origin(classOf[naogateway.api.RobotSnapshot])
      api should not be gateway
      val entries = classEntries(api)
      entries should contain allOf ("naogateway/api/RobotSnapshot.class",
        "naogateway/api/TrafficStats.class", "naogateway/api/GatewayStats.class",
        "naogateway/api/VisionFrame.class", "naogateway/api/RobotFailure.class")
      entries.filter(e =>
        Seq("Gateway$", "RobotActor", "Outbox", "ResponseActor", "NoResponseActor", "VisionActor", "KeepAliveStep")
          .exists(n => e.split('/').last.startsWith(n))) shouldBe empty
    }

    "not be in the gateway's classes a second time" in {
      classEntries(gateway).filter(e =>
        e.endsWith("/RobotSnapshot.class") || e.endsWith("/TrafficStats.class")) shouldBe empty
    }
  }

  "The gateway's integration specs" should {
    "be a module of their own, not the simulator's tests" in {
      val integration = origin(classOf[naogateway.integration.GatewayFixture])
      val simTests = origin(classOf[naogateway.sim.TestGateway])
      integration should not be simTests
      classEntries(integration) should contain("naogateway/integration/GatewayIntegrationSpec.class")
      classEntries(simTests).filter(e =>
        e.startsWith("naogateway/integration/") || e.startsWith("naogateway/gateway/")) shouldBe empty
    }
  }

  /** The class path of this JVM without the gateway's, the simulator's and the apps' own classes. */
  private def withoutGateway: Seq[String] = {
    val dropped = Set(gateway, origin(classOf[naogateway.sim.FleetSettings]), origin(classOf[apps.StatusModel])).map(
      _.toAbsolutePath)
    System.getProperty("java.class.path").split(File.pathSeparator).toSeq.filterNot(e =>
      dropped(Paths.get(e).toAbsolutePath))
  }

  /** The errors scalac reports (typer only, nothing written) for `sources` against `classpath`. */
  private def compileErrors(classpath: Seq[String], sources: Seq[(String, String)]): Vector[String] =
    withTempDir("apps-probe") { out =>
      val settings = new Settings()
      settings.processArgumentString(s"-Ystop-after:typer -d $out")
      settings.classpath.value = classpath.mkString(File.pathSeparator)
      val reporter = new StoreReporter(settings)
      val global = new Global(settings, reporter)
      new global.Run().compileSources(sources.map { case (name, text) => new BatchSourceFile(name, text) }.toList)
      reporter.infos.toVector.filter(_.severity == reporter.ERROR).map(i =>
        s"${i.pos.source.file.name}:${i.pos.line}: ${i.msg}")
    }

  /** Every apps main source file's text, found from the module's or the repository's directory. */
  private def appsSources: Seq[(String, String)] = {
    val root = Seq(Paths.get("src/main/scala/apps"), Paths.get("apps/src/main/scala/apps")).find(Files.isDirectory(_))
      .getOrElse(fail("apps sources not found"))
    val files = Using.resource(Files.walk(root))(_.iterator.asScala.filter(_.toString.endsWith(".scala")).toVector)
    files.sortBy(_.toString).map { p =>
      root.relativize(p).toString -> new String(Files.readAllBytes(p), java.nio.charset.StandardCharsets.UTF_8)
    }
  }

  "The apps" should {
    "all compile without the gateway's and the simulator's classes (as the build compiles them)" in {
      val sources = appsSources
      sources.map(_._1) should contain allOf ("StatusPrinter.scala", "web/WebServer.scala",
        "control/ControlServer.scala", "zeromq/ZeroMqEndpoint.scala")
      compileErrors(withoutGateway, sources) shouldBe empty
    }

    "refuse, against that class path, a probe that names a gateway internal or the simulator" in {
      val probes = Seq(
        "naogateway.gateway.Gateway" -> "object Probe { val g = naogateway.gateway.Gateway }",
        "GatewaySettings" ->
          "object Probe { def s(system: akka.actor.typed.ActorSystem[_]) = naogateway.gateway.GatewaySettings(system) }",
        "Fleet" -> "import naogateway.sim.Fleet\nobject Probe { val f = Fleet }"
      )
      probes.foreach { case (name, text) =>
        val errors = compileErrors(withoutGateway, Seq("Probe.scala" -> s"package probe\n$text\n"))
        withClue(text)(errors should not be empty)
        errors.mkString("\n") should (include(name.split('.').last) or
          include("object gateway is not a member of package naogateway"))
      }
    }

    "still compile a probe that reads the gateway through the api's view" in {
      compileErrors(
        withoutGateway,
        Seq("Probe.scala" -> ("package probe\nobject Probe {\n" +
          "  def robots(view: naogateway.api.GatewayView) = view.robots()\n" +
          "  def line(s: naogateway.api.GatewayStats) = s.toString\n}\n"))
      ) shouldBe empty
    }
  }
}
