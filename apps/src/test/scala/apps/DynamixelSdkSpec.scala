package apps

import java.io.File
import java.net.{InetSocketAddress, ServerSocket}
import java.nio.charset.StandardCharsets
import java.nio.file.Files
import java.util.concurrent.TimeUnit

import scala.concurrent.duration._
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import apps.zeromq.PythonEnv
import naogateway.integration.GatewayFixture
import naogateway.sim.bus.{BioloidBus, BusTcpServer}
import naogateway.sim.{FirmwareSettings, SimulatedRobot, SimulatedRobotSettings}
import naogateway.testkit.TestLoopback
import naogateway.testkit.TempFiles.{withTempDir, withTempFile}
import naogateway.api.RobotOnline
import naogateway.gateway.{BusBridgeServer, BusBridgeSettings}

/** The official ROBOTIS DynamixelSDK (`dynamixel-sdk` from PyPI, protocol 1.0, unmodified; pinned in
  * apps/python/requirements.txt) against what we wrote: first the emulated bus straight on a TCP port, which validates
  * the emulation (18 servos ping as AX-12A, the control table reads and writes, a goal position reads back as the
  * present position once reached, the HaViMo2 answers at id 100); then the same through the gateway's bus bridge and
  * the secure stream to a simulated robot (docs/protocol.md 6.9). socat makes the pseudo-terminal the SDK opens, as the
  * README's "Calibrating a HaViMo2 over WiFi" does. Cancelled when python3, venv, pip or socat is missing.
  */
/** The official DynamixelSDK's script (src/test/python/dynamixel/sdk_bus.py) behind socat's pseudo-terminal, as a team
  * reaches a robot's bus (README, "Calibrating a HaViMo2 over WiFi"); shared by every spec that drives a bus with it.
  */
object SdkBus extends org.scalatest.Assertions with org.scalatest.matchers.should.Matchers {

  private lazy val script = new File(PythonEnv.root, "src/test/python/dynamixel/sdk_bus.py")

  /** socat's name, or the test is cancelled: the SDK test cannot run without it. */
  def socat(): String =
    Try(new ProcessBuilder("socat", "-V").redirectErrorStream(true).start())
      .filter(p => p.waitFor(10, TimeUnit.SECONDS) && p.exitValue() == 0)
      .map(_ => "socat").getOrElse(cancel("socat is not installed (.ci/setup.d/socat.sh): the SDK test cannot run"))

  /** socat's pseudo-terminal in front of 127.0.0.1:`port`, for the length of `body`. socat connects at once; when the
    * bridge refuses it (the one tool's place not yet free) it exits, and is started again.
    */
  def throughPty[T](port: Int)(body: File => T): T = withTempDir("dxl") { dirPath =>
    val dir = dirPath.toFile
    val link = new File(dir, "ttyDXL")
    def start() = new ProcessBuilder(socat(), s"pty,link=${link.getPath},raw,echo=0", s"tcp:127.0.0.1:$port")
      .redirectErrorStream(true).redirectOutput(new File(dir, "socat.log")).start()
    var process = start()
    try {
      val deadline = 15.seconds.fromNow
      // Up and staying up for a moment: a refused connection ends socat within milliseconds.
      def up() = link.exists() && process.isAlive && { Thread.sleep(300); process.isAlive && link.exists() }
      while (!up() && deadline.hasTimeLeft()) {
        if (!process.isAlive) process = start()
        Thread.sleep(100)
      }
      withClue(Try(new String(Files.readAllBytes(new File(dir, "socat.log").toPath), StandardCharsets.UTF_8))) {
        (link.exists() && process.isAlive) shouldBe true
      }
      body(link)
    } finally {
      process.destroy()
      process.waitFor(5, TimeUnit.SECONDS)
    }
  }

  /** Runs the SDK script against `device` for servos 1-18 (plus `extra` arguments); its exit code and output. */
  def run(device: File, extra: Seq[String]): (Int, String) = {
    val python = PythonEnv.python()
    withTempFile("sdk-bus", ".log") { log =>
      PythonEnv.run(Seq(python.getPath, script.getPath, "--device", device.getPath, "--ids", "1-18") ++ extra,
        3.minutes, log.toFile)
    }
  }
}

class DynamixelSdkSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  import SdkBus.{socat, throughPty}

  /** Runs the SDK script against `device`; its exit code and output. */
  private def sdk(device: File, extra: String*): (Int, String) = SdkBus.run(device, Seq("--camera") ++ extra)

  "the official DynamixelSDK" should {
    "ping all 18 servos and the HaViMo2 of the emulated bus, read and write their control tables" in {
      PythonEnv.python()
      val server = new BusTcpServer(BioloidBus(0L))
      try
        throughPty(server.port) { device =>
          val (code, out) = sdk(device)
          withClue(out) {
            code shouldBe 0
            (1 to 18).foreach(id => out should include(s""""$id": 12"""))
            out should include(""""100": 0""")
          }
          server.current.servos.find(_.id == 2).flatMap(_.position) shouldBe Some(700)
        }
      finally server.close()
    }

    "do the same through the gateway's bus bridge, the secure stream and a simulated robot" in {
      PythonEnv.python()
      socat()
      val f = new GatewayFixture(testKit, naogateway.integration.BusBridgeSpec.Patient)
      val robotId = 2
      val base = {
        val s = new ServerSocket(0, 1, java.net.InetAddress.getLoopbackAddress)
        try s.getLocalPort - robotId
        finally s.close()
      }
      val bridge = spawn(BusBridgeServer(f.gateway, BusBridgeSettings(enabled = true, basePort = base), None))
      val started = createTestProbe[SimulatedRobot.StartResult]()
      spawn(SimulatedRobot(
          SimulatedRobotSettings(FirmwareSettings(robotId), f.addresses.robots,
            bindAddress = new InetSocketAddress(TestLoopback.address(), 0)).withStream(f.settings.stream),
          Some(started.ref)
        ))
      val robot = started.receiveMessage(10.seconds) match {
        case SimulatedRobot.Started(_, ref, _) => ref
        case other                             => fail(s"robot did not start: $other")
      }
      try {
        f.awaitEvent(10.seconds) { case RobotOnline(`robotId`, _) => () }
        // The bridge listens once the robot's stream is known; socat's connection is tried until it is taken.
        eventually(timeout(20.seconds)) { new java.net.Socket("127.0.0.1", base + robotId).close() }
        Thread.sleep(500)
        throughPty(base + robotId) { device =>
          // Over the bridge a round trip crosses the WiFi twice: the SDK's packet timeout is raised (README).
          val (code, out) = sdk(device, "--latency-ms", "250")
          withClue(out) {
            code shouldBe 0
            (1 to 18).foreach(id => out should include(s""""$id": 12"""))
          }
        }
      } finally {
        robot ! SimulatedRobot.Stop(system.ignoreRef)
        testKit.stop(bridge)
        f.stop()
      }
    }
  }
}
