package naogateway.sim.bus

import com.google.protobuf.ByteString
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.proto.{BusBridge, BusResult}
import naogateway.sim.{Pose, Scene}
import naogateway.wire.{Dynamixel, HaViMo}

/** The emulated bus byte for byte, without actors: the AX-12A control tables, motion on the bus's clock, status-return
  * levels, broadcast and sync write, the HaViMo2's capture cycle, and the robot's handling of bridged requests.
  */
class BioloidBusSpec extends AnyWordSpec with Matchers {
  import Dynamixel._

  private val second = 1000000000L
  private def status(bytes: Array[Byte]): Status = Dynamixel.status(bytes).getOrElse(fail(s"no status: ${bytes.toSeq}"))
  private def word(s: Status): Int = s.params(0) | (s.params(1) << 8)

  "the bus's servos" should {
    val bus = BioloidBus(0L)
    "answer a ping from every id 1 to 18 and nobody else" in {
      BioloidBus.ServoIds.foreach { id =>
        status(bus.transact(packet(id, Ping, Nil))._2) shouldBe Status(id, 0, Vector.empty)
      }
      bus.transact(packet(19, Ping, Nil))._2 shouldBe empty
      bus.transact(packet(0xfe, Ping, Nil))._2 shouldBe empty
    }
    "read the AX-12A's control table at the e-Manual's addresses" in {
      word(status(bus.transact(packet(5, Read, Seq(Ax12.ModelNumber, 2)))._2)) shouldBe 12
      status(bus.transact(packet(5, Read, Seq(Ax12.IdAddress, 1)))._2).params shouldBe Vector(5)
      status(bus.transact(packet(5, Read, Seq(Ax12.StatusReturnLevel, 1)))._2).params shouldBe Vector(2)
      status(bus.transact(packet(5, Read, Seq(Ax12.ReturnDelayTime, 1)))._2).params shouldBe Vector(250)
      word(status(bus.transact(packet(5, Read, Seq(Ax12.PresentPosition, 2)))._2)) shouldBe 512
      status(bus.transact(packet(5, Read, Seq(Ax12.PresentVoltage, 1)))._2).params shouldBe Vector(120)
      status(bus.transact(packet(5, Read, Seq(48, 5)))._2).error shouldBe RangeError
    }
    "move the present position to a written goal at the moving speed, on the bus's clock" in {
      val (spedUp, _) = bus.transact(packet(3, Write, Seq(Ax12.MovingSpeed, 100, 0)))
      val (moving, answer) = spedUp.transact(packet(3, Write, Seq(Ax12.GoalPosition, 0xbc, 0x02))) // 700
      status(answer) shouldBe Status(3, 0, Vector.empty)
      status(moving.transact(packet(3, Read, Seq(Ax12.TorqueEnable, 1)))._2).params shouldBe Vector(1)
      // 100 speed units: 0.111 rpm each, about 227 units a second, so 188 units take about 0.83 s.
      val later = moving.advance(second / 2)
      val halfway = word(status(later.transact(packet(3, Read, Seq(Ax12.PresentPosition, 2)))._2))
      halfway should (be > 600 and be < 700)
      status(later.transact(packet(3, Read, Seq(Ax12.Moving, 1)))._2).params shouldBe Vector(1)
      val arrived = moving.advance(2 * second)
      word(status(arrived.transact(packet(3, Read, Seq(Ax12.PresentPosition, 2)))._2)) shouldBe 700
      status(arrived.transact(packet(3, Read, Seq(Ax12.Moving, 1)))._2).params shouldBe Vector(0)
      arrived.servos.find(_.id == 3).flatMap(_.position) shouldBe Some(700)
      arrived.servos.map(_.id) shouldBe BioloidBus.ServoIds.toVector
    }
    "refuse a goal beyond 1023 and a write to a read-only address" in {
      status(bus.transact(packet(3, Write, Seq(Ax12.GoalPosition, 0, 4)))._2).error shouldBe RangeError
      status(bus.transact(packet(3, Write, Seq(Ax12.PresentPosition, 0)))._2).error shouldBe RangeError
      status(bus.transact(packet(3, 0x33, Nil))._2).error shouldBe InstructionError
    }
    "answer as the status-return level says" in {
      val (quiet, _) = bus.transact(packet(4, Write, Seq(Ax12.StatusReturnLevel, 1)))
      quiet.transact(packet(4, Write, Seq(Ax12.Led, 1)))._2 shouldBe empty
      status(quiet.transact(packet(4, Read, Seq(Ax12.Led, 1)))._2).params shouldBe Vector(0)
      val (silent, _) = quiet.transact(packet(4, Write, Seq(Ax12.StatusReturnLevel, 0)))
      silent.transact(packet(4, Read, Seq(Ax12.Led, 1)))._2 shouldBe empty
      status(silent.transact(packet(4, Ping, Nil))._2).id shouldBe 4
    }
    "act on broadcast, sync write and a registered write without answering" in {
      val (torque, none) = bus.transact(packet(BroadcastId, Write, Seq(Ax12.TorqueEnable, 1)))
      none shouldBe empty
      torque.tables.forall(_.torqueOn) shouldBe true
      val (synced, nothing) = bus.transact(packet(BroadcastId, SyncWrite, Seq(Ax12.GoalPosition, 2, 1, 0, 1, 2, 0, 3)))
      nothing shouldBe empty
      synced.tables.find(_.id == 1).get.goal shouldBe 256
      synced.tables.find(_.id == 2).get.goal shouldBe 768
      val (registered, _) = bus.transact(packet(6, RegWrite, Seq(Ax12.GoalPosition, 0, 1)))
      registered.tables.find(_.id == 6).get.goal shouldBe 512
      val (acted, _) = registered.transact(packet(BroadcastId, Action, Nil))
      acted.tables.find(_.id == 6).get.goal shouldBe 256
    }
    "answer a packet with a bad checksum with the checksum error bit, and noise with nothing" in {
      val bad = packet(1, Ping, Nil)
      bad(bad.length - 1) = (bad.last + 1).toByte
      status(bus.transact(bad)._2) shouldBe Status(1, ChecksumError, Vector.empty)
      bus.transact(bad.drop(1))._2 shouldBe empty
    }
  }

  "the HaViMo2 at id 100" should {
    val view = Scene.regions(Scene(1.0, 0.0), Pose(0.0, 0.0, 0.0), 0.0, 0.0)
    "see the ball in the scene" in { view.map(_.colour) should contain(Scene.BallColour) }
    val bus = BioloidBus(0L, view)
    "hold the capture of power-up in its region buffer, slot i at address 16·i" in {
      val record = status(bus.transact(packet(100, Read, Seq(16, 16)))._2).params
      record(0) shouldBe 1
      HaViMo.decodeRegions(record.map(_.toByte).toArray).toOption.get shouldBe Vector(view.head)
      status(bus.transact(packet(100, Read, Seq(16 * 15, 16)))._2).params.forall(_ == 0) shouldBe true
    }
    "answer nothing while a capture is processed, then show the new one" in {
      val (capturing, ack) =
        bus.withVolts(12.0).seeing(Vector.empty).transact(packet(100, HaViMo2Device.CapRegion, Nil))
      ack shouldBe empty
      capturing.transact(packet(100, Ping, Nil))._2 shouldBe empty
      capturing.camera.captures shouldBe 1
      // The public examples' capture, a write to address 0, answers nothing either.
      bus.transact(packet(100, Write, Seq(0, 0))) match {
        case (b, a) => (a.length, b.camera.captures) shouldBe ((0, 1))
      }
      val done = capturing.advance(HaViMo2Device.DefaultCaptureNanos)
      status(done.transact(packet(100, Ping, Nil))._2).id shouldBe 100
      status(done.transact(packet(100, Read, Seq(16, 16)))._2).params.forall(_ == 0) shouldBe true
    }
    "read the same regions and grid over the bus as the scene gives" in {
      val (next, frame) = BusWork.cameraCycle(bus, withGrid = true)
      frame.map(_.records.toVector) shouldBe Some(HaViMo.encodeRegions(view).toOption.get.toVector)
      frame.flatMap(_.grid).map(_.toVector) shouldBe Some(Scene.grid(view).toVector)
      // Model number 0, as ROBOTIS's headers list the HaViMo2.
      word(status(bus.transact(packet(100, Read, Seq(0, 2)))._2)) shouldBe 0
      status(bus.transact(packet(100, HaViMo2Device.ReadGrid, Seq(47, 16)))._2).params shouldBe
        Scene.grid(view).toVector.slice(752, 768).map(_ & 0xff)
      status(bus.transact(packet(100, HaViMo2Device.ReadGrid, Seq(47, 17)))._2).error shouldBe RangeError
      next.camera.captures shouldBe 1
      BusWork.cameraCycle(next, withGrid = false)._2 shouldBe None
    }
  }

  "a bridged request" should {
    val bus = BioloidBus(0L)
    def bridge(bytes: Array[Byte], gateClosed: Boolean = false) =
      BusWork.bridge(bus, BusBridge(9, request = Some(ByteString.copyFrom(bytes))), gateClosed)._2
    "bring back the status packet with BUS_OK" in {
      val reply = bridge(packet(2, Read, Seq(Ax12.PresentPosition, 2)))
      reply.sequence shouldBe 9
      reply.result shouldBe Some(BusResult.BUS_OK)
      word(status(reply.reply.get.toByteArray)) shouldBe 512
      bridge(packet(BroadcastId, Write, Seq(Ax12.Led, 1))) shouldBe BusBridge(9, result = Some(BusResult.BUS_OK))
    }
    "say BUS_TIMEOUT for a servo that does not answer, BUS_MALFORMED for a damaged packet" in {
      bridge(packet(42, Ping, Nil)).result shouldBe Some(BusResult.BUS_TIMEOUT)
      bridge(Array[Byte](-1, -1, 1, 9)).result shouldBe Some(BusResult.BUS_MALFORMED)
      BusWork.bridge(bus, BusBridge(3), gateClosed = false)._2.result shouldBe Some(BusResult.BUS_MALFORMED)
    }
    "say BUS_GATE_CLOSED without touching the bus while the game runs" in {
      val (after, reply) = BusWork.bridge(bus,
        BusBridge(1, request = Some(ByteString.copyFrom(packet(2, Write, Seq(Ax12.GoalPosition, 0, 1))))),
        gateClosed = true)
      reply shouldBe BusBridge(1, result = Some(BusResult.BUS_GATE_CLOSED))
      after shouldBe bus
    }
  }
}
