package naogateway.wire.gamecontroller

import java.nio.charset.StandardCharsets

import scala.collection.immutable.ArraySeq

import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.wire.gamecontroller.GameControllerError._

/** Versions 19 and 12 of the control packet, the monitor's `RGTD` and return packets of version 4: round trips and
  * refusals.
  */
class ModernCodecSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {
  import GameControllerGenerators._

  implicit override val generatorDrivenConfig: PropertyCheckConfiguration =
    PropertyCheckConfiguration(minSuccessful = 200)

  private def ascii(s: String): Array[Byte] = s.getBytes(StandardCharsets.US_ASCII)
  private def seq(values: Int*): ArraySeq[Byte] = ArraySeq.from(values.map(_.toByte))
  private def encoded(data: GameControlData): Array[Byte] =
    GameControllerCodec.encodeControl(data).fold(err => fail(err.describe), identity)

  private val v19Sample = GameControllerVectors.bytes("v19-playing.bin")
  private val v12Sample = GameControllerVectors.bytes("v12-playing.bin")

  "Version 19" should {
    "round-trip every valid value through exactly 198 bytes with a u8 version" in {
      forAll(controlV19) { data =>
        val bytes = encoded(data)
        bytes.length shouldBe 198
        bytes(4) shouldBe 19.toByte
        GameControllerCodec.decodeControl(bytes) shouldBe Right(data)
      }
    }
    "give back the identical bytes for every packet it accepts" in {
      val packets = for {
        tail <- Gen.containerOfN[Array, Byte](193, Gen.choose(Byte.MinValue, Byte.MaxValue))
        stopped <- Gen.oneOf(0, 1)
        half <- Gen.oneOf(0, 1)
      } yield {
        val bytes = ascii("RGme") ++ Array(19.toByte) ++ tail
        bytes(8) = stopped.toByte
        bytes(12) = half.toByte
        bytes
      }
      forAll(packets) { bytes =>
        val data = GameControllerCodec.decodeControl(bytes).fold(err => fail(err.describe), identity)
        GameControllerCodec.encodeControl(data).map(_.toSeq) shouldBe Right(bytes.toSeq)
      }
    }
    "refuse every size but 198" in {
      (5 to 800).filter(_ != 198).foreach { n =>
        GameControllerCodec.decodeControl(java.util.Arrays.copyOf(v19Sample, n)) shouldBe Left(WrongSize("RGme", 19,
            198, n))
      }
    }
    "refuse stopped and firstHalf bytes other than 0 or 1" in {
      GameControllerCodec.decodeControl(v19Sample.updated(8, 2.toByte)) shouldBe Left(InvalidField("stopped", 2L))
      GameControllerCodec.decodeControl(v19Sample.updated(12, 7.toByte)) shouldBe Left(InvalidField("firstHalf", 7L))
    }
    "read 255 as no kicking team, and refuse to encode team number 255" in {
      val none = GameControllerCodec.decodeControl(v19Sample.updated(13, 0xff.toByte))
      none.map { case d: HslControlData => d.kickingTeam; case _ => fail() } shouldBe Right(None)
      val d = controlV19.sample.get
      GameControllerCodec.encodeControl(d.copy(kickingTeam = Some(255))) shouldBe
        Left(OutOfRange(19, "kickingTeam", 255L, 0L, 254L))
    }
    "refuse values that do not fit the fields and player lists of the wrong length" in {
      val d = controlV19.sample.get
      GameControllerCodec.encodeControl(d.copy(secsRemaining = 40000L)) shouldBe
        Left(OutOfRange(19, "secsRemaining", 40000L, -32768L, 32767L))
      GameControllerCodec.encodeControl(d.copy(team1 = d.team1.copy(messageBudget = 70000))) shouldBe
        Left(OutOfRange(19, "team1.messageBudget", 70000L, 0L, 65535L))
      GameControllerCodec.encodeControl(d.copy(team0 = d.team0.copy(players = d.team0.players.take(11)))) shouldBe
        Left(WrongLength("team0.players", 20, 11))
    }
    "come under RGTD for a monitor, and be refused there in any other version" in {
      forAll(controlV19) { data =>
        val bytes = GameControllerCodec.encodeTrueData(data).fold(err => fail(err.describe), identity)
        bytes.take(4).toSeq shouldBe ascii("RGTD").toSeq
        bytes.drop(4).toSeq shouldBe encoded(data).drop(4).toSeq
        GameControllerCodec.decodeTrueData(bytes) shouldBe Right(data)
        GameControllerCodec.decodeControl(bytes) shouldBe Left(WrongHeader("RGme", seq('R', 'G', 'T', 'D')))
      }
      GameControllerCodec.decodeTrueData(v19Sample) shouldBe Left(WrongHeader("RGTD", seq('R', 'G', 'm', 'e')))
      val v12AsTrue = ascii("RGTD") ++ v12Sample.drop(4)
      GameControllerCodec.decodeTrueData(v12AsTrue) shouldBe Left(UnknownVersion("RGTD", seq(12, 0)))
      val short = ascii("RGTD") ++ v19Sample.drop(4).take(100)
      GameControllerCodec.decodeTrueData(short) shouldBe Left(WrongSize("RGTD", 19, 198, 104))
    }
  }

  "Version 12" should {
    "round-trip every valid value through exactly 688 bytes with a u16 version" in {
      forAll(controlV12) { data =>
        val bytes = encoded(data)
        bytes.length shouldBe 688
        bytes.slice(4, 6).toSeq shouldBe seq(12, 0)
        GameControllerCodec.decodeControl(bytes) shouldBe Right(data)
      }
    }
    "refuse every size but 688" in {
      (6 to 1400).filter(_ != 688).foreach { n =>
        GameControllerCodec.decodeControl(java.util.Arrays.copyOf(v12Sample, n)) shouldBe Left(WrongSize("RGme", 12,
            688, n))
      }
      GameControllerCodec.decodeControl(ascii("RGme") :+ 12.toByte) shouldBe Left(TooShort(6, 5))
    }
    "refuse a version byte 12 whose u16 is not 12" in {
      GameControllerCodec.decodeControl(v12Sample.updated(5, 1.toByte)) shouldBe
        Left(UnknownVersion("RGme", seq(12, 1, v12Sample(6), v12Sample(7))))
    }
    "refuse a goalkeeper flag other than 0 or 1" in {
      // team[0] starts at 24; its coach at 24 + 7 + 253 = 284, its first player at 290, whose flag is byte 295.
      GameControllerCodec.decodeControl(v12Sample.updated(295, 2.toByte)) shouldBe
        Left(InvalidField("team0.players[0].goalKeeper", 2L))
    }
    "refuse values that do not fit and raw fields of the wrong length" in {
      val d = controlV12.sample.get
      GameControllerCodec.encodeControl(d.copy(dropInTime = -1)) shouldBe Left(OutOfRange(12, "dropInTime", -1L, 0L,
          65535L))
      GameControllerCodec.encodeControl(d.copy(secondaryStateInfo = seq(1, 2, 3))) shouldBe
        Left(WrongLength("secondaryStateInfo", 4, 3))
      GameControllerCodec.encodeControl(d.copy(team1 = d.team1.copy(coachMessage = seq(1)))) shouldBe
        Left(WrongLength("team1.coachMessage", 253, 1))
    }
  }

  "Every version" should {
    "be told apart by its version field alone, and a 2014 value relabelled as a newer version be refused" in {
      forAll(control) { data =>
        val bytes = encoded(data)
        GameControllerCodec.decodeControl(bytes).map(_.version) shouldBe Right(data.version)
      }
      val v8 = controlV8.sample.get
      GameControllerCodec.encodeControl(v8.copy(version = GameControlVersion.V19)) shouldBe Left(InvalidField("version",
          19L))
    }
    "refuse the other versions' sizes as a wrong size of the version read" in {
      val sizes = GameControlVersion.all.map(_.packetBytes)
      val samples: Map[GameControlVersion, GameControlData] = Map(
        GameControlVersion.V20 -> controlV20.sample.get,
        GameControlVersion.V19 -> controlV19.sample.get,
        GameControlVersion.V12 -> controlV12.sample.get,
        GameControlVersion.V8 -> controlV8.sample.get,
        GameControlVersion.V7 -> controlV7.sample.get
      )
      for {
        version <- GameControlVersion.all
        size <- sizes if size != version.packetBytes
      } {
        val bytes = java.util.Arrays.copyOf(encoded(samples(version)), size)
        GameControllerCodec.decodeControl(bytes) shouldBe Left(WrongSize("RGme", version.number, version.packetBytes,
            size))
      }
    }
  }

  "Return packets of version 4" should {
    "round-trip every valid status through exactly 32 bytes, player before team" in {
      forAll(returnStatus) { status =>
        val bytes = GameControllerCodec.encodeStatus(status).fold(err => fail(err.describe), identity)
        bytes.length shouldBe 32
        bytes.take(8).toSeq shouldBe (ascii("RGrt") ++ Array(4, status.player, status.team, if (status.fallen) 1 else 0)
          .map(_.toByte)).toSeq
        GameControllerCodec.decodeStatus(bytes) shouldBe Right(status)
      }
    }
    "hold the floats little-endian at offsets 8 to 31" in {
      val bytes = GameControllerCodec.encodeStatus(ReturnStatus(3, 12, fallen = true, (1000f, -500f, 1.5f), -1f,
          (250f, 0f))).toOption.get
      bytes.slice(8, 12).toSeq shouldBe seq(0x00, 0x00, 0x7a, 0x44) // 1000.0f
      bytes.slice(20, 24).toSeq shouldBe seq(0x00, 0x00, 0x80, 0xbf) // -1.0f
    }
    "refuse another size, version 2 bytes, a fallen byte over 1 and NaN" in {
      val ok = GameControllerCodec.encodeStatus(returnStatus.sample.get).toOption.get
      (5 to 100).filter(_ != 32).foreach { n =>
        GameControllerCodec.decodeStatus(java.util.Arrays.copyOf(ok, n)) shouldBe Left(WrongSize("RGrt", 4, 32, n))
      }
      GameControllerCodec.decodeStatus(ok.updated(4, 2.toByte)) shouldBe Left(UnknownVersion("RGrt", seq(2)))
      GameControllerCodec.decodeReturn(ok) shouldBe Left(UnknownVersion("RGrt", seq(4)))
      GameControllerCodec.decodeStatus(ok.updated(7, 255.toByte)) shouldBe Left(InvalidField("fallen", 255L))
      val nan = ok.clone()
      Array(0x00, 0x00, 0xc0, 0x7f).map(_.toByte).copyToArray(nan, 20) // ballAge = NaN
      GameControllerCodec.decodeStatus(nan) shouldBe Left(NotANumber("ballAge"))
      GameControllerCodec.encodeStatus(ReturnStatus(1, 1, fallen = false, (0f, Float.NaN, 0f), 0f, (0f, 0f))) shouldBe
        Left(NotANumber("pose[1]"))
    }
  }
}
