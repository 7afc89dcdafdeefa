package naogateway.sim

import java.net.InetSocketAddress

import scala.concurrent.duration._

import com.google.protobuf.ByteString
import org.scalatest.EitherValues
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.proto.{BusBridge, BusResult}
import naogateway.sim.bus.{Ax12, BodyPostures}
import naogateway.wire._

/** The simulated robot's body: its posture moves the 18 AX-12A of its emulated bus (docs/simulator.md 3.2), and the
  * GameController it hears closes its bus bridge while the game runs (docs/protocol.md 6.9).
  */
class FirmwareBodySpec extends AnyWordSpec with Matchers with EitherValues {

  private val ms = 1000000L
  private val gateway = new InetSocketAddress("127.0.0.1", 11011)
  private val settings = FirmwareSettings(robotId = 2)

  private def call(
      state: FirmwareState, method: String, params: Vector[RpcValue], id: Long, at: Long): FirmwareState = {
    val request = MessageContents(0, rpcRequest = Some(RpcCall("motion", method, params, Some(id)).toProto))
    RobotFirmware.receive(state, MessageContents.encodeFrame(request).value, gateway, at)._1
  }

  private def goals(s: FirmwareState): Vector[Int] = s.bus.tables.sortBy(_.id).map(_.goal)

  // Present positions as a read over the bus finds them (address 36), at the firmware's time.
  private def present(s: FirmwareState): Vector[Int] =
    s.bus.advance(s.now).tables.sortBy(_.id).map(t => math.round(t.position).toInt)

  private def telemetryPositions(s: FirmwareState): Vector[Int] =
    RobotFirmware.servoTelemetry(s).servos.map(_.position.get).toVector

  "The simulated robot's body" should {
    "power up resting in its sitting pose, torque off" in {
      val s = RobotFirmware.boot(settings, 0)
      goals(s) shouldBe BodyPostures.goals(BodyPostures.Pose.Sit)
      present(s) shouldBe BodyPostures.goals(BodyPostures.Pose.Sit)
      s.bus.tables.forall(!_.torqueOn) shouldBe true
    }

    "move its servos to the stand table when it stands, arriving with the posture change" in {
      val s0 = RobotFirmware.boot(settings, 0)
      val moving = call(s0, "posture", Vector(RpcValue.Text("stand")), 1, 10 * ms)
      goals(moving) shouldBe BodyPostures.goals(BodyPostures.Pose.Stand)
      moving.bus.tables.forall(_.torqueOn) shouldBe true
      // Half way the legs are between the tables; at the end of the stand-up time all are there.
      val half = RobotFirmware.advance(moving, 10 * ms + settings.standUpTime.toNanos / 2)._1
      present(half) should not be BodyPostures.goals(BodyPostures.Pose.Sit)
      present(half) should not be BodyPostures.goals(BodyPostures.Pose.Stand)
      val stood = RobotFirmware.advance(moving, 10 * ms + settings.standUpTime.toNanos + 50 * ms)._1
      stood.posture shouldBe Posture.Stand
      present(stood) shouldBe BodyPostures.goals(BodyPostures.Pose.Stand)
      telemetryPositions(stood) shouldBe BodyPostures.goals(BodyPostures.Pose.Stand)
    }

    "alternate its two step poses while it walks, stand when it stops, and sit when it sits" in {
      val s0 = RobotFirmware.boot(settings, 0)
      val t0 = settings.standUpTime.toNanos + 100 * ms
      val stood = RobotFirmware.advance(call(s0, "posture", Vector(RpcValue.Text("stand")), 1, 0), t0)._1
      val walk = Vector(RpcValue.Number(0.1f), RpcValue.Number(0f), RpcValue.Number(0f))
      var s = call(stood, "walk", walk, 2, t0)
      val seen = (0 until 8).map { i =>
        val t = t0 + i * 200 * ms
        s = RobotFirmware.advance(call(s, "walk", walk, 10 + i, t), t)._1
        goals(s)
      }.distinct
      seen.toSet shouldBe Set(BodyPostures.goals(BodyPostures.Pose.StepLeft),
        BodyPostures.goals(BodyPostures.Pose.StepRight))
      val t1 = t0 + 1600 * ms
      val stopped = call(s, "stop", Vector.empty, 30, t1)
      goals(stopped) shouldBe BodyPostures.goals(BodyPostures.Pose.Stand)
      val sat = call(stopped, "posture", Vector(RpcValue.Text("sit")), 31, t1 + ms)
      goals(sat) shouldBe BodyPostures.goals(BodyPostures.Pose.Sit)
      present(RobotFirmware.advance(sat, t1 + ms + settings.sitDownTime.toNanos + 50 * ms)._1) shouldBe
        BodyPostures.goals(BodyPostures.Pose.Sit)
    }

    "stand up again when a walk's lease runs out" in {
      val t0 = settings.standUpTime.toNanos + 100 * ms
      val stood =
        RobotFirmware.advance(call(RobotFirmware.boot(settings, 0), "posture", Vector(RpcValue.Text("stand")), 1, 0),
          t0)._1
      val walking = call(stood, "walk", Vector(RpcValue.Number(0.1f), RpcValue.Number(0f), RpcValue.Number(0f)), 2, t0)
      goals(walking) should not be BodyPostures.goals(BodyPostures.Pose.Stand)
      val lapsed = RobotFirmware.advance(walking, t0 + settings.walkLease.toNanos + ms)._1
      lapsed.posture shouldBe Posture.Stand
      goals(lapsed) shouldBe BodyPostures.goals(BodyPostures.Pose.Stand)
    }

    "leave a goal written over the bus bridge alone until the posture changes" in {
      val s0 = RobotFirmware.boot(settings, 0)
      val write = BusBridge(1,
        request = Some(ByteString.copyFrom(Dynamixel.packet(3, Dynamixel.Write,
              Seq(Ax12.GoalPosition, 0x00, 0x02)))))
      val (written, _) = RobotFirmware.busBridge(s0, write, 5 * ms)
      val later = RobotFirmware.advance(written, 2000 * ms)._1
      later.bus.tables.find(_.id == 3).get.goal shouldBe 0x200
      val stood = call(later, "posture", Vector(RpcValue.Text("stand")), 1, 2001 * ms)
      stood.bus.tables.find(_.id == 3).get.goal shouldBe BodyPostures.goals(BodyPostures.Pose.Stand)(2)
    }
  }

  "The simulated robot's bus bridge" should {
    "answer BUS_GATE_CLOSED from the simulated GameController's READY to the end of PLAYING, and serve again after" in {
      val gc = SimulatedGameControllerSettings(gateway)
      def packetAt(elapsed: FiniteDuration) =
        SimulatedGameController.packets(gc, SimulatedGameController.momentAt(gc, elapsed.toNanos), 1).head
      val ping = BusBridge(1, request = Some(ByteString.copyFrom(Dynamixel.packet(1, Dynamixel.Ping, Nil))))
      def heard(s: FirmwareState, elapsed: FiniteDuration, at: Long): BusResult = {
        val after = RobotFirmware.receive(s, packetAt(elapsed), gateway, at)._1
        BusBridgeFrame.decode(RobotFirmware.busBridge(after, ping, at + ms)._2).get._2.result.get
      }
      val s0 = RobotFirmware.boot(settings, 0)
      val initial = gc.initial / 2
      val ready = gc.initial + gc.ready / 2
      val set = gc.initial + gc.ready + gc.set / 2
      val playing = gc.initial + gc.ready + gc.set + gc.playing / 2
      val finished = gc.initial + gc.ready + gc.set + gc.playing + gc.finished / 2
      Seq(initial, ready, set, playing, finished).zipWithIndex.map { case (e, i) =>
        heard(s0, e, (i + 1) * ms)
      } shouldBe
        Seq(BusResult.BUS_OK, BusResult.BUS_GATE_CLOSED, BusResult.BUS_GATE_CLOSED, BusResult.BUS_GATE_CLOSED,
          BusResult.BUS_OK)
    }

    "let a stranger's control packets change nothing: neither close the bridge before play nor open it during play" in {
      val gc = SimulatedGameControllerSettings(gateway)
      def packetAt(elapsed: FiniteDuration) =
        SimulatedGameController.packets(gc, SimulatedGameController.momentAt(gc, elapsed.toNanos), 1).head
      val ping = BusBridge(1, request = Some(ByteString.copyFrom(Dynamixel.packet(1, Dynamixel.Ping, Nil))))
      def result(s: FirmwareState, at: Long): BusResult =
        BusBridgeFrame.decode(RobotFirmware.busBridge(s, ping, at)._2).get._2.result.get
      val ours = new InetSocketAddress("127.0.0.1", 3838)
      val stranger = new InetSocketAddress("127.0.0.99", 3838)
      val s0 = RobotFirmware.boot(settings.copy(gameControllerSource = Some(ours.getAddress)), 0)
      val playing = gc.initial + gc.ready + gc.set + gc.playing / 2
      // Before the game: a stranger's PLAYING packets, three of them, neither close the bridge nor get an answer.
      val (strangerPlays, answers) = (1 to 3).foldLeft((s0, Vector.empty[Outgoing])) { case ((s, out), i) =>
        val (next, o) = RobotFirmware.receive(s, packetAt(playing), stranger, i * ms)
        (next, out ++ o.filter(_.to != Destination.Gateway))
      }
      answers shouldBe empty
      strangerPlays.game shouldBe None
      strangerPlays.stats.gameControllerIgnored shouldBe 3
      result(strangerPlays, 10 * ms) shouldBe BusResult.BUS_OK
      // During play, by the team's GameController: a stranger's INITIAL does not open the bridge again.
      val playingNow = RobotFirmware.receive(s0, packetAt(playing), ours, 20 * ms)._1
      result(playingNow, 21 * ms) shouldBe BusResult.BUS_GATE_CLOSED
      val strangerInitial = RobotFirmware.receive(playingNow, packetAt(gc.initial / 2), stranger, 22 * ms)._1
      strangerInitial.game shouldBe playingNow.game
      result(strangerInitial, 23 * ms) shouldBe BusResult.BUS_GATE_CLOSED
    }
  }
}
