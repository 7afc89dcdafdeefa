package apps

import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel
import java.nio.file.{Files, Path}

import scala.concurrent.Await
import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import apps.zeromq.PythonEnv
import naogateway.access.GatewayAccess
import naogateway.api.{GameStateUpdated, GatewayAddresses, GatewayEvent, RobotOnline}
import naogateway.gateway.{Gateway, GatewaySettings}
import naogateway.sim.{Fleet, FleetSettings, SimulatedGameController, SimulatedGameControllerSettings}
import naogateway.testkit.{TempFiles, TestLoopback}

object RecordingPythonSpec {
  val directory: Path = Files.createTempDirectory("recording-python-spec")

  val config: String =
    s"""naogateway {
       |  link { bind-address = "127.0.0.1", robot-port = 0 }
       |  game-controller { bind-address = "127.0.0.1", port = 0 }
       |  recording { enabled = on, directory = "${directory.toString}" }
       |}
       |""".stripMargin
}

/** A recording made by a real gateway with simulated robots and GameController, read by the official Python mcap
  * package.
  */
class RecordingPythonSpec extends ScalaTestWithActorTestKit(RecordingPythonSpec.config) with AnyWordSpecLike
    with LogCapturing {
  import RecordingPythonSpec._

  // After the kit's shutdown, which stops a gateway a failed test left running and so closes its file.
  override def afterAll(): Unit =
    try super.afterAll()
    finally TempFiles.deleteRecursively(directory)

  "A gateway's recording" must {
    "be read by the official mcap Python reader: datagrams byte for byte, Status through its schema, the decisions" in {
      PythonEnv.python() // cancels here when Python is missing, before anything is started
      val gateway = spawn(Gateway(GatewaySettings(system)), "gateway")
      val addresses = createTestProbe[GatewayAddresses]()
      gateway ! GatewayAccess.GetAddresses(addresses.ref)
      val bound = addresses.receiveMessage(10.seconds)
      val events = createTestProbe[GatewayEvent]()
      gateway ! GatewayAccess.Subscribe(events.ref)
      val fleet = Await.result(Fleet.start(system,
          FleetSettings(bound.robots, Vector(1, 2), faithfulLink = false,
            firstAddress = TestLoopback.block(2))), 30.seconds)
      val gc =
        spawn(SimulatedGameController(SimulatedGameControllerSettings(bound.gameController.get, interval = 100.millis)),
          "gc")
      val stranger = DatagramChannel.open().bind(new InetSocketAddress(TestLoopback.address(0), 0))
      val strangerAt = stranger.getLocalAddress.asInstanceOf[InetSocketAddress]
      val odd = Array[Byte](0, 1, 2, 3, -1, -2, 'x', 'y')
      val robot2 = fleet.address(2).getOrElse(fail("robot 2 has no address"))
      try {
        events.fishForMessage(20.seconds) {
          case RobotOnline(2, _) => akka.actor.testkit.typed.FishingOutcome.Complete
          case _                 => akka.actor.testkit.typed.FishingOutcome.ContinueAndIgnore
        }
        events.fishForMessage(10.seconds) {
          case _: GameStateUpdated => akka.actor.testkit.typed.FishingOutcome.Complete
          case _                   => akka.actor.testkit.typed.FishingOutcome.ContinueAndIgnore
        }
        stranger.send(ByteBuffer.wrap(odd), bound.robots)
        Thread.sleep(500)
      } finally {
        testKit.stop(gc)
        Await.result(fleet.stop(), 30.seconds)
        testKit.stop(gateway, 15.seconds) // closes the file
        stranger.close()
      }

      val files = Files.list(directory).iterator().asScala.map(_.toString).filter(_.endsWith(".mcap")).toVector.sorted
      files should not be empty
      val (code, output) = PythonEnv.script("read_recording.py", files, 120.seconds)
      withClue(output.linesIterator.take(40).mkString("\n")) {
        code shouldBe 0
        val lines = output.linesIterator.toVector
        val Datagram = """datagram (\d+) (\w+) (\w+) (\S+) (\S+) robot (\S+) ([0-9a-f]*)""".r
        val datagrams = lines.collect { case Datagram(_, port, dir, from, to, robot, hex) =>
          (port, dir, from, to, robot, hex)
        }
        datagrams should contain(("ROBOT_PORT", "RECEIVED",
            s"${strangerAt.getAddress.getHostAddress}:${strangerAt.getPort}",
            s"127.0.0.1:${bound.robots.getPort}", "-", odd.map(b => f"${b & 0xff}%02x").mkString))
        // GameController packets as they came ("RGme"), and the robots' keep-alives (FU-Remote frames, 00 2a).
        datagrams.exists { case (port, dir, _, _, _, hex) =>
          port == "GAME_CONTROLLER" && dir == "RECEIVED" && hex.startsWith("52476d65")
        } shouldBe true
        datagrams.exists { case (port, dir, _, _, robot, hex) =>
          port == "ROBOT_PORT" && dir == "RECEIVED" && robot == "1" && hex.startsWith("002a")
        } shouldBe true
        // What the gateway sent robot 2 (its option pull, probes), to the robot's receive address.
        val two = robot2.getAddress.getHostAddress + ":" + robot2.getPort
        datagrams.exists { case (port, dir, _, to, _, _) =>
          port == "ROBOT_PORT" && dir == "SENT" && to == two
        } shouldBe true
        val Status = """status (\d+) (\d+) team (\d+) agent (\S+) timestamp (\d+)""".r
        val statuses = lines.collect { case Status(robot, _, team, agent, _) => (robot.toInt, team.toInt, agent) }
        statuses.map(_._1).distinct.sorted shouldBe Vector(1, 2)
        statuses.map(_._2).distinct shouldBe Vector(1)
        val decisions = lines.filter(_.startsWith("decision "))
        decisions.exists(d =>
          d.contains("\"decision\": \"robot-online\"") && d.contains("\"robotId\": 1")) shouldBe true
        decisions.exists(d => d.contains("\"decision\": \"game-state\"")) shouldBe true
        decisions.exists(d => d.contains("\"decision\": \"send\"")) shouldBe true
      }
    }
  }
}
