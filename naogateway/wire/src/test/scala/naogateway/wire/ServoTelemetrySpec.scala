package naogateway.wire

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.proto.{RobotHealth, ServoState, ServoTelemetry, Status}

/** Servo telemetry in the keep-alive (docs/protocol.md 6.8): its bytes, and the keep-alive decoder reading it. */
class ServoTelemetrySpec extends AnyWordSpec with Matchers {

  private def hex(b: Array[Byte]) = b.map(x => f"${x & 0xff}%02X").mkString(" ")

  /** Eighteen AX-12As near the centre, one of them silent (its last read found no valid answer). */
  private val eighteen = ServoTelemetry(
    (1 to 18).map { id =>
      if (id == 7) ServoState(id, silent = Some(true))
      else ServoState(id, Some(500 + id), Some(if (id % 2 == 0) -id * 10 else id * 10), Some(121), Some(38 + id % 5))
    },
    busErrors = Some(3)
  )

  private val keepAlive = MessageContents(
    2,
    status = Some(Status(timestamp = Some(5000L), teamID = Some(12))),
    robotHealth = Some(RobotHealth(batteryVoltage = Some(12.1f), uptimeMs = Some(5000), bootId = Some(1))),
    servoTelemetry = Some(eighteen)
  )

  "A ServoState" should {
    "travel as protocol.md 6.8's fields, the load as sint32 (negative: zigzag)" in {
      // id 3, position 512, load -40, voltage 12.1 V, temperature 41 °C.
      val bytes = ServoState(3, Some(512), Some(-40), Some(121), Some(41)).toByteArray
      hex(bytes) shouldBe "08 03 10 80 04 18 4F 20 79 28 29"
      ServoState.parseFrom(bytes).load shouldBe Some(-40)
    }

    "travel as its id and the silent flag alone when the servo did not answer" in {
      hex(ServoState(7, silent = Some(true)).toByteArray) shouldBe "08 07 38 01"
    }
  }

  "The keep-alive decoder" should {
    "read a keep-alive with 18 servos on its one-pass path, as the general path reads it" in {
      val bytes = keepAlive.toProtobuf
      val fast = KeepAliveReader.read(bytes, 0, bytes.length)
      fast should not be null
      fast shouldBe keepAlive
      MessageContents.general(bytes, 0, bytes.length) shouldBe Right(keepAlive)
      val servos = fast.servoTelemetry.get.servos
      servos.map(_.id) shouldBe (1 to 18)
      servos(6) shouldBe ServoState(7, silent = Some(true))
      servos(1).load shouldBe Some(-20)
      fast.servoTelemetry.get.busErrors shouldBe Some(3)
    }

    "put the extension after robotHealth, by ascending number (6.8)" in {
      val bytes = keepAlive.toProtobuf
      val healthTag = Array(0x8a, 0xbc, 0x03).map(_.toByte) // field 7105, length-delimited
      val servoTag = Array(0x92, 0xbc, 0x03).map(_.toByte) // field 7106, length-delimited
      val at = bytes.indexOfSlice(servoTag.toSeq)
      at should be > bytes.indexOfSlice(healthTag.toSeq)
      at should be > 0
    }

    "read the whole frame, legacy and compact header, and gzip-flagged" in {
      for {
        form <- Seq(HeaderForm.Legacy, HeaderForm.Compact)
        gzip <- Seq(false, true)
      } {
        val frame = MessageContents.encodeFrame(keepAlive, form, gzip).toOption.get
        MessageContents.decodeFrame(frame).map(_._2) shouldBe Right(keepAlive)
      }
    }

    "read a keep-alive without the extension as one without telemetry" in {
      val without = keepAlive.copy(servoTelemetry = None)
      val bytes = without.toProtobuf
      MessageContents.parse(bytes).map(_.servoTelemetry) shouldBe Right(None)
      MessageContents.parse(bytes) shouldBe Right(without)
    }

    "read an empty telemetry (no servos configured) as present and empty" in {
      val empty = keepAlive.copy(servoTelemetry = Some(ServoTelemetry()))
      MessageContents.parse(empty.toProtobuf).map(_.servoTelemetry) shouldBe Right(Some(ServoTelemetry()))
    }

    "fit 18 servos in one keep-alive frame well inside the robot's buffer" in {
      val frame = MessageContents.encodeFrame(keepAlive).toOption.get
      val withoutServos = MessageContents.encodeFrame(keepAlive.copy(servoTelemetry = None)).toOption.get
      val added = frame.length - withoutServos.length
      // protocol.md 6.8: "about 300 bytes" for 18 servos.
      added should (be > 200 and be < 320)
      frame.length should be < WireLimits.MaxDatagramBytes
    }
  }
}
