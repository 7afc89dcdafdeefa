package apps.zeromq

import java.io.File
import java.net.ServerSocket
import java.nio.charset.StandardCharsets
import java.nio.file.Files
import java.util.concurrent.TimeUnit

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.annotation.tailrec
import scala.util.{Failure, Success, Try}

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.Assertions
import org.scalatest.wordspec.AnyWordSpecLike
import org.zeromq.{ZMQ, ZMQException}

import naogateway.sim.{FirmwareSettings, ZeroMqSimulatedRobot}
import naogateway.gateway.{Gateway, GatewaySettings, ZeroMqRobot}
import naogateway.testkit.TempFiles
import robotmiddleware.{MiddlewareSettings, RobotMiddleware}

/** A Python virtual environment under target/ with the client's pinned packages, made once and reused. */
object PythonEnv extends Assertions {

  /** The checkout's root: the folder that holds apps/python (tests may run in the root or in apps/). */
  lazy val root: File =
    Iterator.iterate(new File(".").getAbsoluteFile)(_.getParentFile).takeWhile(_ != null)
      .find(d => new File(d, "apps/python/pyproject.toml").isFile)
      .getOrElse(fail("cannot find apps/python from " + new File(".").getAbsolutePath))

  /** Runs `command` in the checkout's root; its exit code and everything it printed (also kept in `log`). */
  def run(
      command: Seq[String], within: FiniteDuration, log: File, env: Map[String, String] = Map.empty): (Int, String) = {
    val builder = new ProcessBuilder(command.asJava).directory(root).redirectErrorStream(true).redirectOutput(log)
    env.foreach { case (k, v) => builder.environment().put(k, v) }
    val process = builder.start()
    if (!process.waitFor(within.toSeconds, TimeUnit.SECONDS)) {
      process.destroyForcibly()
      fail(s"${command.mkString(" ")} did not finish within $within")
    }
    process.exitValue() -> new String(Files.readAllBytes(log.toPath), StandardCharsets.UTF_8)
  }

  /** The one venv of every Python test, and the requirements it is made from. */
  lazy val venv: File = new File(root, "apps/target/python-venv")
  lazy val requirements: File = new File(root, "apps/python/requirements.txt")

  /** A venv at `venv` with `requirements` installed (made once, reused while they stay the same), or why there is none:
    * python3 missing, no venv module, or pip unable to install (no network, no registry). `env` is given to pip. The
    * test JVMs of two modules may ask at once (apps' and the root's firmware specs): a lock file beside the venv lets
    * one make it while the other waits.
    */
  def environment(venv: File = venv, requirements: File = requirements, env: Map[String, String] = Map.empty)
      : Either[String, File] =
    synchronized {
      venv.getParentFile.mkdirs()
      val lock = java.nio.channels.FileChannel.open(new File(venv.getParentFile, s"${venv.getName}.lock").toPath,
        java.nio.file.StandardOpenOption.CREATE, java.nio.file.StandardOpenOption.WRITE)
      try {
        lock.lock()
        made(venv, requirements, env)
      } finally lock.close()
    }

  private def made(venv: File, requirements: File, env: Map[String, String]): Either[String, File] = {
    val log = new File(venv.getParentFile, s"${venv.getName}-setup.log")
    val python = new File(venv, "bin/python")
    val wanted = new String(Files.readAllBytes(requirements.toPath), StandardCharsets.UTF_8)
    val stamp = new File(venv, "requirements.installed")
    val current = Try(new String(Files.readAllBytes(stamp.toPath), StandardCharsets.UTF_8)).toOption
    if (!Try(run(Seq("python3", "--version"), 30.seconds, log)).toOption.exists(_._1 == 0))
      Left("python3 is not available")
    else if (python.isFile && current.contains(wanted)) Right(python)
    else {
      TempFiles.deleteRecursively(venv.toPath)
      val (venvCode, venvOut) = run(Seq("python3", "-m", "venv", venv.getPath), 2.minutes, log)
      if (venvCode != 0) Left(s"python3 -m venv failed (is the venv module installed?):\n${venvOut.takeRight(2000)}")
      else {
        val (pipCode, pipOut) =
          run(Seq(python.getPath, "-m", "pip", "install", "--disable-pip-version-check", "-q", "-r",
              requirements.getPath), 8.minutes, log, env)
        if (pipCode != 0) {
          // A half-made venv is not reused: the next run tries again.
          TempFiles.deleteRecursively(venv.toPath)
          Left(
            s"pip could not install ${root.toPath.relativize(requirements.toPath)} (no network or no package registry?):\n${pipOut.takeRight(2000)}")
        } else {
          Files.write(stamp.toPath, wanted.getBytes(StandardCharsets.UTF_8))
          Right(python)
        }
      }
    }
  }

  /** The venv's python; cancels the test, saying why, when python3, venv or pip cannot provide it. */
  def python(): File = environment().fold(why => cancel(s"$why: the Python test cannot run"), identity)

  /** Runs a script of apps/python with `args`; its exit code and everything it printed. */
  def script(name: String, args: Seq[String], within: FiniteDuration): (Int, String) = {
    val py = python()
    val gen = new File(root, "apps/target/python-gen")
    // Generated afresh each run, so the classes always match proto/.
    TempFiles.deleteRecursively(gen.toPath)
    run(
      py.getPath +: "-u" +: new File(root, s"apps/python/$name").getPath +: args,
      within,
      new File(root, s"apps/target/$name.log"),
      Map("NAOGATEWAY_PY_GEN" -> gen.getPath, "PYTHONPATH" -> new File(root, "apps/python").getPath,
        "PYTHONDONTWRITEBYTECODE" -> "1")
    )
  }
}

object PythonClientSpec {
  val config: String =
    """naogateway {
      |  link { bind-address = "127.0.0.1", robot-port = 0 }
      |  game-controller.enabled = off
      |}
      |apps.zeromq { enabled = on, bind = "tcp://127.0.0.1:*", publish = "tcp://127.0.0.1:*" }
      |# One loop thread for each test's endpoint, and one for the first test's ZeroMQ robot link.
      |apps.zeromq.dispatcher.thread-pool-executor.fixed-pool-size = 4
      |""".stripMargin

  /** The simulated robot, started on a free port. It binds the endpoint it is given and cannot tell a port it picked
    * itself, so the port is picked here; one that another process takes before the robot binds it is picked again.
    */
  @tailrec def startRobot(attempts: Int = 5): ZeroMqSimulatedRobot = {
    val port = {
      val s = new ServerSocket(0)
      try s.getLocalPort
      finally s.close()
    }
    val robot = new ZeroMqSimulatedRobot(FirmwareSettings(robotId = 20), s"tcp://127.0.0.1:$port")
    val started = Try(robot.start())
    started match {
      case Success(_) => robot
      case Failure(e: ZMQException) if e.getErrorCode == ZMQ.Error.EADDRINUSE.getCode && attempts > 1 =>
        startRobot(attempts - 1)
      case Failure(e) => throw e
    }
  }
}

class PythonClientSpec extends ScalaTestWithActorTestKit(PythonClientSpec.config) with AnyWordSpecLike
    with LogCapturing {
  import PythonClientSpec._

  "The Python example" must {
    "stand a simulated ZeroMQ robot up, walk it, stop it and print its status, through the endpoint" in {
      PythonEnv.python() // cancels here when Python is missing, before anything is started
      val robot = startRobot()
      try {
        val configured = GatewaySettings(system)
        val gateway = spawn(Gateway(configured.copy(zeromq = configured.zeromq.copy(robots = Vector(ZeroMqRobot(20,
                robot.endpoint))))),
          "gateway")
        val middleware = spawn(RobotMiddleware(gateway, MiddlewareSettings(system)), "middleware")
        val endpoint = spawn(ZeroMqEndpoint(middleware, ZeroMqSettings(system)), "zeromq")
        val probe = createTestProbe[ZeroMqEndpoint.Addresses]()
        endpoint ! ZeroMqEndpoint.GetAddresses(probe.ref)
        val addresses = probe.receiveMessage(10.seconds)
        val startX = robot.firmware.get.pose.x

        val (code, output) = PythonEnv.script("example_walk.py",
          Seq("--endpoint", addresses.requests, "--publish", addresses.publish, "--robot", "20"), 90.seconds)
        withClue(output) {
          code shouldBe 0
          val lines = output.linesIterator.toVector
          lines should contain("robots: [20]")
          lines should contain("posture: stand")
          lines should contain("stopped")
          val Status = """status of robot 20: battery (\d+\.\d\d) V, posture (\w+), link (\w+)""".r
          val status = lines.collectFirst { case Status(battery, posture, link) => (battery.toDouble, posture, link) }
          status shouldBe defined
          status.get._1 shouldBe 12.4 +- 0.2
          status.get._2 shouldBe "stand"
          // The posture motion held the robot's socket for 1.5 s without a keep-alive: the quality may show it.
          Set("good", "degraded") should contain(status.get._3)
        }
        // The simulated robot really walked: about 0.1 m/s for about a second.
        robot.firmware.get.pose.x - startX should be > 0.05
        robot.firmware.get.posture.name shouldBe "stand"
      } finally robot.stop()
    }

    "read a robot another app holds, be refused an absurd walk in words, and see stop's posture and the link at once" in {
      val python = PythonEnv.python()
      val f = new naogateway.integration.GatewayFixture(testKit)
      try {
        f.robot(34)
        f.robot(35)
        var online = Set.empty[Int]
        while (online != Set(34, 35))
          online += f.awaitEvent(30.seconds) { case naogateway.api.RobotOnline(id, _) if id == 34 || id == 35 => id }
        val middleware = spawn(RobotMiddleware(f.gateway, MiddlewareSettings(system)), "middleware-reads")
        val endpoint = spawn(ZeroMqEndpoint(middleware, ZeroMqSettings(system)), "zeromq-reads")
        val probe = createTestProbe[ZeroMqEndpoint.Addresses]()
        endpoint ! ZeroMqEndpoint.GetAddresses(probe.ref)
        val addresses = probe.receiveMessage(10.seconds)
        // Another app holds robot 34's walk lease, above the endpoint's priority.
        val referee =
          scala.concurrent.Await.result(robotmiddleware.RobotClient.connect(system, middleware, "referee", 99),
            10.seconds)
        scala.concurrent.Await.result(referee.acquire(34, naogateway.wire.ActuatorGroup.Walk), 10.seconds)
        val code =
          s"""from naogateway_client import GatewayClient, GatewayError
             |c = GatewayClient("${addresses.requests}", "${addresses.publish}")
             |print("read:", c.call(34, "motion", "getPosture"), c.call(34, "system", "battery") > 10)
             |try:
             |    c.walk(34, 0.1, 0.0, 0.0)
             |except GatewayError as e:
             |    print("held:", e.category)
             |print("posture:", c.posture(35, "stand"))
             |try:
             |    c.walk(35, 100.0, 0.0, 0.0)
             |except GatewayError as e:
             |    print("absurd:", e.text)
             |print("walk:", c.walk(35, 0.1, 0.0, 0.0))
             |print("stop:", c.stop(35))
             |s = c.status(35)
             |print("status:", s["posture"], s["online"], s["link"] in ("good", "degraded"))
             |sv = c.servos(35)
             |print("servos:", [x["id"] for x in sv] == list(range(1, 19)), all(11 < x["voltage"] < 13 for x in sv),
             |      any(x["hot"] or x["low_voltage"] for x in sv))
             |c.close()
             |""".stripMargin
        val gen = new File(PythonEnv.root, "apps/target/python-gen")
        val log = new File(PythonEnv.root, "apps/target/reads.log")
        val (exit, output) = PythonEnv.run(
          Seq(python.getPath, "-u", "-c", code),
          90.seconds,
          log,
          Map("NAOGATEWAY_PY_GEN" -> gen.getPath, "PYTHONPATH" -> new File(PythonEnv.root, "apps/python").getPath,
            "PYTHONDONTWRITEBYTECODE" -> "1")
        )
        withClue(output) {
          exit shouldBe 0
          output.linesIterator.toVector shouldBe Vector(
            "read: sit True",
            "held: lease",
            "posture: stand",
            "absurd: robot error: out of range: vx 100.0, allowed -0.3..0.3",
            "walk: True",
            "stop: True",
            "status: stand True True",
            "servos: True True False"
          )
        }
        referee.close()
        testKit.stop(endpoint)
      } finally f.stop()
    }

    "send without waiting and call through both doors, in order, refused as a call is, the send's answer dropped" in {
      val python = PythonEnv.python()
      val f = new naogateway.integration.GatewayFixture(testKit)
      try {
        val (robot, _) = f.robot(33)
        f.awaitEvent(30.seconds) { case naogateway.api.RobotOnline(33, _) => () }
        val middleware = spawn(RobotMiddleware(f.gateway, MiddlewareSettings(system)), "middleware-doors")
        val endpoint = spawn(ZeroMqEndpoint(middleware, ZeroMqSettings(system)), "zeromq-doors")
        val probe = createTestProbe[ZeroMqEndpoint.Addresses]()
        endpoint ! ZeroMqEndpoint.GetAddresses(probe.ref)
        val addresses = probe.receiveMessage(10.seconds)
        // A referee above the endpoint's priority holds the head: the client's send of a head turn is refused.
        val connecting = robotmiddleware.RobotClient.connect(system, middleware, "referee", 99)
        val referee = scala.concurrent.Await.result(connecting, 10.seconds)
        scala.concurrent.Await.result(referee.acquire(33, naogateway.wire.ActuatorGroup.Head), 10.seconds)
        val code =
          s"""from naogateway_client import GatewayClient, GatewayError
             |c = GatewayClient("${addresses.requests}", "${addresses.publish}")
             |print("send:", c.send(33, "speech", "say", "first"))
             |print("call:", c.call(33, "speech", "say", "second"))
             |print("send:", c.send(33, "speech", "say", "third"))
             |print("dropped:", c.send(33, "nosuch", "method"))
             |try:
             |    c.send(33, "motion", "head", 0.5, 0.0)
             |except GatewayError as e:
             |    print("refused:", e.category)
             |c.close()
             |""".stripMargin
        val gen = new File(PythonEnv.root, "apps/target/python-gen")
        val log = new File(PythonEnv.root, "apps/target/doors.log")
        val (exit, output) = PythonEnv.run(
          Seq(python.getPath, "-u", "-c", code),
          90.seconds,
          log,
          Map("NAOGATEWAY_PY_GEN" -> gen.getPath, "PYTHONPATH" -> new File(PythonEnv.root, "apps/python").getPath,
            "PYTHONDONTWRITEBYTECODE" -> "1")
        )
        withClue(output) {
          exit shouldBe 0
          output.linesIterator.toVector shouldBe
            Vector("send: None", "call: True", "send: None", "dropped: None", "refused: lease")
        }
        val heard = createTestProbe[Vector[naogateway.sim.ReceivedCall]]()
        eventually(timeout(30.seconds)) {
          robot ! naogateway.sim.SimulatedRobot.GetReceivedCalls(heard.ref)
          val calls = heard.receiveMessage(10.seconds).map(_.call)
          calls.filter(_.name == "speech.say").flatMap(_.params) shouldBe
            Vector("first", "second", "third").map(naogateway.wire.RpcValue.Text(_))
          calls.map(_.name) should contain("nosuch.method")
          calls.map(_.name) should not contain "motion.head"
        }
        referee.close()
        testKit.stop(endpoint)
      } finally f.stop()
    }
  }
}
