package naogateway.launcher

import java.net.{InetSocketAddress, ServerSocket}
import java.util.concurrent.TimeUnit

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import com.typesafe.config.ConfigFactory
import org.scalatest.wordspec.AnyWordSpecLike

import apps.control.{ControlServer, ControlSettings, FleetStub}
import naogateway.wire.RpcValue

class RobotCtlSpec extends ScalaTestWithActorTestKit(ConfigFactory.load()) with AnyWordSpecLike with LogCapturing {

  private val fleet = new FleetStub(1000)
  private lazy val control: String = {
    val server =
      spawn(ControlServer.withInterface(fleet, ControlSettings(system).copy(host = "127.0.0.1", port = 0)), "control")
    val probe = createTestProbe[InetSocketAddress]()
    server ! ControlServer.GetAddress(probe.ref)
    s"127.0.0.1:${probe.receiveMessage(10.seconds).getPort}"
  }

  /** What `robotctl args` prints, on standard output and on standard error, and its exit code. */
  private final case class Run(code: Int, out: Vector[String], err: Vector[String])

  private def robotctl(args: Seq[String], env: Map[String, String] = Map.empty): Run = {
    val out = Vector.newBuilder[String]
    val err = Vector.newBuilder[String]
    val code = RobotCtl.run(args, env.get, out += _, err += _)
    Run(code, out.result(), err.result())
  }

  /** A loopback port with nothing listening on it. */
  private def closedPort(): Int = {
    val s = new ServerSocket(0);
    try s.getLocalPort
    finally s.close()
  }

  "robotctl's command line" should {
    "read status, call with typed parameters, and watch with a default duration" in {
      RobotCtl.parse(Seq("status")) shouldBe Right(RobotCtl.Request.Status)
      RobotCtl.parse(Seq("call", "2", "motion", "head", "0.5", "-0.2")) shouldBe
        Right(RobotCtl.Request.Call(2, "motion", "head", Vector(RpcValue.Number(0.5f), RpcValue.Number(-0.2f))))
      RobotCtl.parse(Seq("call", "1", "speech", "say", "hello")) shouldBe
        Right(RobotCtl.Request.Call(1, "speech", "say", Vector(RpcValue.Text("hello"))))
      RobotCtl.parse(Seq("watch", "3")) shouldBe Right(RobotCtl.Request.Watch(3, 10))
      RobotCtl.parse(Seq("watch", "3", "5")) shouldBe Right(RobotCtl.Request.Watch(3, 5))
    }
    "say clearly what is wrong" in {
      RobotCtl.parse(Seq("call", "x", "m", "n")) shouldBe Left("robot id 'x' is not a number")
      RobotCtl.parse(Seq("watch", "1", "-4")) shouldBe Left("'-4' is not a number of seconds")
      RobotCtl.parse(Seq("dance")) shouldBe Left(RobotCtl.usage)
      RobotCtl.parse(Nil) shouldBe Left(RobotCtl.usage)
    }
    "find the control port in --control, else in NAOGATEWAY_CONTROL, else at the default" in {
      val env = Map("NAOGATEWAY_CONTROL" -> "127.0.0.2:7000")
      RobotCtl.invocation(Seq("--control", "127.0.0.3:8000", "status"), env.get) shouldBe Right(
        "127.0.0.3:8000" -> RobotCtl.Request.Status)
      RobotCtl.invocation(Seq("--control=127.0.0.3:8000", "status"), env.get) shouldBe Right(
        "127.0.0.3:8000" -> RobotCtl.Request.Status)
      RobotCtl.invocation(Seq("status"), env.get) shouldBe Right("127.0.0.2:7000" -> RobotCtl.Request.Status)
      RobotCtl.invocation(Seq("status"), _ => None) shouldBe Right("127.0.0.1:11019" -> RobotCtl.Request.Status)
    }
  }

  "robotctl against a gateway's control port" should {
    "print a status line per robot, with link quality and loss, and exit 0" in {
      val run = robotctl(Seq("--control", control, "status"))
      run.err shouldBe empty
      run.code shouldBe RobotCtl.ExitOk
      run.out.size shouldBe 1001
      run.out.head.split("\\s+").toList shouldBe List("id", "address", "state", "link", "battery", "posture", "role",
        "rtt", "loss", "clock", "drift", "leases")
      run.out(1).split("\\s+").toList shouldBe List("1", "127.0.0.1:20001", "online", "good", "12.25", "V", "sit",
        "striker", "1.5", "ms", "25", "%", "±1.4", "ms", "+250", "ppm", "-")
      // Which app holds which lease (FleetStub: robot 2's walk is teleop's), and a robot held safe (3).
      run.out(2) should endWith(" walk=teleop")
      run.out(3) should endWith(" - HELD SAFE")
    }

    "make a call with its parameters typed as on the command line, the port taken from the environment" in {
      val run = robotctl(Seq("call", "3", "speech", "say", "hello world"), Map("NAOGATEWAY_CONTROL" -> control))
      run shouldBe Run(RobotCtl.ExitOk, Vector("robot 3: speech.say -> Text(speech.say(Text(hello world)))"),
        Vector.empty)
      fleet.history should contain inOrderElementsOf Vector("acquire 3 speech", "call 3 speech.say", "release 3 speech")
    }

    "print the gateway's error and exit 1 for an unknown robot or a failing call" in {
      robotctl(Seq("--control", control, "call", "5000", "system", "ping")) shouldBe Run(1, Vector.empty,
        Vector("robotctl: no robot 5000 is known"))
      robotctl(Seq("--control", control, "call", "5", "system", "ping")) shouldBe Run(1, Vector.empty,
        Vector("robotctl: robot 5: no such method"))
      robotctl(Seq("--control", control, "watch", "5000")) shouldBe Run(1, Vector.empty,
        Vector("robotctl: no robot 5000 is known"))
    }

    "stream a watch" in {
      val run = robotctl(Seq("--control", control, "watch", "4", "1"))
      run.code shouldBe RobotCtl.ExitOk
      run.out.head should startWith("id ")
      run.out.last shouldBe "watched robot 4 for 1 s"
    }

    "exit 2 with the usage for a wrong command line or address, without connecting" in {
      robotctl(Seq("dance")) shouldBe Run(2, Vector.empty, Vector(RobotCtl.usage))
      robotctl(Seq("--control", "nowhere", "status")) shouldBe
        Run(2, Vector.empty, Vector("robotctl: --control / NAOGATEWAY_CONTROL: 'nowhere' is not host:port"))
      robotctl(Seq("call", "1", "m", "f", "x" * 5000)) shouldBe Run(2, Vector.empty,
        Vector("robotctl: the command is longer than 4096 bytes"))
    }

    "say that no gateway is running, and exit 1, when nothing listens" in {
      val port = closedPort()
      robotctl(Seq("--control", s"127.0.0.1:$port", "status")) shouldBe
        Run(1, Vector.empty, Vector(s"no gateway at 127.0.0.1:$port: is naogateway running?"))
    }

    "start no actor system and load no Akka, Typesafe config or Logback classes" in {
      val java = s"${System.getProperty("java.home")}/bin/java"
      val process =
        new ProcessBuilder(Seq(java, "-verbose:class", "-cp", System.getProperty("java.class.path"),
            "naogateway.launcher.RobotCtl",
            "--control", control, "call", "1", "system", "ping").asJava).redirectErrorStream(true).start()
      val output = scala.io.Source.fromInputStream(process.getInputStream).getLines().toVector
      process.waitFor(60, TimeUnit.SECONDS) shouldBe true
      withClue(output.filterNot(_.contains("[class,load]")).mkString("\n")) { process.exitValue() shouldBe 0 }
      output should contain("robot 1: system.ping -> Text(system.ping())")
      val loaded = output.filter(_.contains("[class,load]"))
      loaded.size should be > 100
      loaded.filter(l =>
        Seq(" akka.", " com.typesafe.config.", " ch.qos.logback.", " org.slf4j.").exists(l.contains)) shouldBe empty
    }
  }
}
