package naogateway.wire.gamecontroller

import java.nio.charset.StandardCharsets

import scala.collection.immutable.ArraySeq
import scala.util.Random

import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.wire.Datagram
import naogateway.wire.gamecontroller.GameControllerError._

/** Round trips, typed refusals and robustness of the GameController codec. */
class GameControllerCodecSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {
  import GameControllerGenerators._

  implicit override val generatorDrivenConfig: PropertyCheckConfiguration =
    PropertyCheckConfiguration(minSuccessful = 300)

  private def ascii(s: String): Array[Byte] = s.getBytes(StandardCharsets.US_ASCII)
  private def bytesOf(values: Int*): Array[Byte] = values.map(_.toByte).toArray
  private def seq(values: Int*): ArraySeq[Byte] = ArraySeq.from(values.map(_.toByte))

  private def encoded(data: GameControlData): Array[Byte] =
    GameControllerCodec.encodeControl(data).fold(err => fail(err.describe), identity)

  private def decoded2014(bytes: Array[Byte]): ControlData2014 = GameControllerCodec.decodeControl(bytes) match {
    case Right(d: ControlData2014) => d
    case other                     => fail(s"not a 2014 packet: $other")
  }

  private val v8Sample: ControlData2014 = controlV8.sample.get
  private val v7Sample: ControlData2014 = controlV7.sample.get

  "GameControllerCodec.encodeControl and decodeControl" should {
    "round-trip every valid version-8 value through exactly 158 bytes" in {
      forAll(controlV8) { data =>
        val bytes = encoded(data)
        bytes.length shouldBe 158
        bytes(4) shouldBe 8.toByte
        GameControllerCodec.decodeControl(bytes) shouldBe Right(data)
      }
    }
    "round-trip every valid version-7 value through exactly 116 bytes with a u32 version" in {
      forAll(controlV7) { data =>
        val bytes = encoded(data)
        bytes.length shouldBe 116
        bytes.slice(4, 8).toSeq shouldBe seq(7, 0, 0, 0)
        GameControllerCodec.decodeControl(bytes) shouldBe Right(data)
      }
    }
    "give back the identical bytes for every packet it accepts" in {
      // Random contents behind a valid header, version and firstHalf byte: every byte must survive.
      def packet(prefix: Array[Byte], size: Int, firstHalfAt: Int): Gen[Array[Byte]] =
        for {
          tail <- Gen.containerOfN[Array, Byte](size - prefix.length, Gen.choose(Byte.MinValue, Byte.MaxValue))
          half <- Gen.oneOf(0, 1)
        } yield {
          val bytes = prefix ++ tail
          bytes(firstHalfAt) = half.toByte
          bytes
        }
      val v8 = packet(ascii("RGme") :+ 8.toByte, 158, firstHalfAt = 8)
      val v7 = packet(ascii("RGme") ++ bytesOf(7, 0, 0, 0), 116, firstHalfAt = 10)
      forAll(Gen.oneOf(v8, v7)) { bytes =>
        val data = GameControllerCodec.decodeControl(bytes).fold(err => fail(err.describe), identity)
        GameControllerCodec.encodeControl(data).map(_.toSeq) shouldBe Right(bytes.toSeq)
      }
    }
  }

  "GameControllerCodec.decodeControl" should {
    "refuse every size but 158 for version 8" in {
      val valid = encoded(v8Sample)
      (5 to 400).filter(_ != 158).foreach { n =>
        val bytes = java.util.Arrays.copyOf(valid, n)
        GameControllerCodec.decodeControl(bytes) shouldBe Left(WrongSize("RGme", 8, 158, n))
      }
    }
    "refuse every size but 116 for version 7" in {
      val valid = encoded(v7Sample)
      (8 to 400).filter(_ != 116).foreach { n =>
        val bytes = java.util.Arrays.copyOf(valid, n)
        GameControllerCodec.decodeControl(bytes) shouldBe Left(WrongSize("RGme", 7, 116, n))
      }
    }
    "refuse a version-7 byte without room for its u32 version" in {
      (5 to 7).foreach { n =>
        GameControllerCodec.decodeControl(ascii("RGme") ++ bytesOf(7, 0, 0).take(n - 4)) shouldBe Left(TooShort(8, n))
      }
    }
    "refuse packets too short for the header or the version" in {
      (0 to 3).foreach { n =>
        GameControllerCodec.decodeControl(ascii("RGme").take(n)) shouldBe Left(TooShort(4, n))
      }
      GameControllerCodec.decodeControl(ascii("RGme")) shouldBe Left(TooShort(5, 4))
    }
    "refuse a wrong header, naming what was found" in {
      val bytes = encoded(v8Sample)
      bytes(3) = 'x'.toByte
      GameControllerCodec.decodeControl(bytes) shouldBe Left(WrongHeader("RGme", seq('R', 'G', 'm', 'x')))
      GameControllerCodec.decodeControl(encoded(v8Sample).updated(0, 0.toByte)) should matchPattern {
        case Left(WrongHeader("RGme", _)) =>
      }
    }
    "refuse a return packet" in {
      val ret = GameControllerCodec.encodeReturn(ReturnData(12, 1, ReturnMessage.Alive)).toOption.get
      GameControllerCodec.decodeControl(ret) shouldBe Left(WrongHeader("RGme", seq('R', 'G', 'r', 't')))
    }
    "refuse every unknown version, naming the bytes found at offset 4" in {
      forAll(Gen.choose(0, 255).filter(v => !Set(7, 8, 12, 19, 20).contains(v)), Gen.choose(100, 200)) {
        (version, size) =>
          val bytes = new Array[Byte](size)
          ascii("RGme").copyToArray(bytes)
          bytes(4) = version.toByte
          bytes(5) = 0x33
          GameControllerCodec.decodeControl(bytes) shouldBe Left(UnknownVersion("RGme", seq(version, 0x33, 0, 0)))
      }
      // A version-9 packet of later years: u16 version 9.
      val v9 = ascii("RGme") ++ bytesOf(9, 0, 4, 6) ++ new Array[Byte](100)
      GameControllerCodec.decodeControl(v9) shouldBe Left(UnknownVersion("RGme", seq(9, 0, 4, 6)))
      // Byte 4 is 7 but the u32 is not: not version 7, and not guessed to be.
      val notSeven = ascii("RGme") ++ bytesOf(7, 1, 0, 0) ++ new Array[Byte](108)
      GameControllerCodec.decodeControl(notSeven) shouldBe Left(UnknownVersion("RGme", seq(7, 1, 0, 0)))
      GameControllerCodec.decodeControl(ascii("RGme") :+ 9.toByte) shouldBe Left(UnknownVersion("RGme", seq(9)))
    }
    "refuse a firstHalf byte other than 0 or 1" in {
      val v8 = encoded(v8Sample).updated(8, 2.toByte)
      GameControllerCodec.decodeControl(v8) shouldBe Left(InvalidField("firstHalf", 2L))
      val v7 = encoded(v7Sample).updated(10, 0xff.toByte)
      GameControllerCodec.decodeControl(v7) shouldBe Left(InvalidField("firstHalf", 255L))
    }
    "keep codes outside the known sets as Unknown" in {
      val bytes = encoded(v8Sample)
      bytes(7) = 9 // gameState
      bytes(9) = 0x7f // kickOffTeam
      bytes(18 + 1) = 5 // teams[0].teamColour
      bytes(18 + 48) = 99 // teams[0].players[0].penalty
      val data = decoded2014(bytes)
      data.gameState shouldBe GameState.Unknown(9)
      data.kickOffTeam shouldBe KickOffTeam.Unknown(0x7f)
      data.team0.teamColour shouldBe TeamColour.Unknown(5)
      data.team0.players.head.penalty shouldBe Penalty.Unknown(99)
    }
    "read version 7's u16 penalties and u32 seconds remaining" in {
      val bytes = encoded(
        v7Sample.copy(
          secsRemaining = 0xfffffffeL,
          team1 = v7Sample.team1.copy(
            players =
              v7Sample.team1.players.updated(10, PlayerInfo(Penalty.Unknown(0x1234), 0xbeef))
          )
        )
      )
      bytes.slice(16, 20).toSeq shouldBe seq(0xfe, 0xff, 0xff, 0xff)
      bytes.slice(112, 116).toSeq shouldBe seq(0x34, 0x12, 0xef, 0xbe)
      val data = decoded2014(bytes)
      data.secsRemaining shouldBe 0xfffffffeL
      data.team1.players(10) shouldBe PlayerInfo(Penalty.Unknown(0x1234), 0xbeef)
    }
    "never throw, for arbitrary bytes" in {
      forAll(bytes(400)) { bytes =>
        noException should be thrownBy GameControllerCodec.decodeControl(bytes)
      }
    }
  }

  "Every decoder and the classifier" should {
    "never throw on GameController prefixes followed by random tails of every length 0..200" in {
      val random = new Random(0x5eed)
      val prefixes = List(
        ascii("RGme"),
        ascii("RGme") :+ 8.toByte,
        ascii("RGme") ++ bytesOf(7, 0, 0, 0),
        ascii("RGme") :+ 7.toByte,
        ascii("RGrt"),
        ascii("RGrt") :+ 2.toByte,
        ascii("RG")
      )
      for {
        prefix <- prefixes
        length <- 0 to 200
        _ <- 1 to 10
      } {
        val tail = new Array[Byte](length)
        random.nextBytes(tail)
        val bytes = prefix ++ tail
        noException should be thrownBy {
          GameControllerCodec.decodeControl(bytes)
          GameControllerCodec.decodeReturn(bytes)
          Datagram.classify(bytes)
        }
      }
    }
    "never throw on arbitrary bytes" in {
      forAll(bytes(1500)) { bytes =>
        noException should be thrownBy {
          GameControllerCodec.decodeControl(bytes)
          GameControllerCodec.decodeReturn(bytes)
          Datagram.classify(bytes)
        }
      }
    }
  }

  "GameControllerCodec.encodeControl" should {
    "refuse fields the version lacks and require fields it has" in {
      GameControllerCodec.encodeControl(v7Sample.copy(packetNumber = Some(1))) shouldBe
        Left(UnexpectedField(7, "packetNumber"))
      GameControllerCodec.encodeControl(v8Sample.copy(packetNumber = None)) shouldBe
        Left(MissingField(8, "packetNumber"))
      GameControllerCodec.encodeControl(v8Sample.copy(secondaryTime = None)) shouldBe
        Left(MissingField(8, "secondaryTime"))
      val v8WithGoal = v8Sample.copy(team1 = v8Sample.team1.copy(goalColour = Some(GoalColour.Blue)))
      GameControllerCodec.encodeControl(v8WithGoal) shouldBe
        Left(UnexpectedField(8, "team1.goalColour"))
      GameControllerCodec.encodeControl(v7Sample.copy(team0 = v7Sample.team0.copy(goalColour = None))) shouldBe
        Left(MissingField(7, "team0.goalColour"))
      val v7WithCoach = v7Sample.copy(team0 = v7Sample.team0.copy(coach = Some(PlayerInfo.Unpenalised)))
      GameControllerCodec.encodeControl(v7WithCoach) shouldBe
        Left(UnexpectedField(7, "team0.coach"))
      // A version-8 value relabelled as version 7 carries fields version 7 would lose.
      GameControllerCodec.encodeControl(v8Sample.copy(version = GameControlVersion.V7)) should matchPattern {
        case Left(UnexpectedField(7, _)) =>
      }
    }
    "refuse values that do not fit the version's field widths" in {
      GameControllerCodec.encodeControl(v8Sample.copy(secsRemaining = 40000L)) shouldBe
        Left(OutOfRange(8, "secsRemaining", 40000L, -32768L, 32767L))
      GameControllerCodec.encodeControl(v7Sample.copy(secsRemaining = -1L)) shouldBe
        Left(OutOfRange(7, "secsRemaining", -1L, 0L, 0xffffffffL))
      GameControllerCodec.encodeControl(v8Sample.copy(gameState = GameState.Unknown(256))) shouldBe
        Left(OutOfRange(8, "gameState", 256L, 0L, 255L))
      val bigPenalty = PlayerInfo(Penalty.Unknown(300), 0)
      GameControllerCodec.encodeControl(
        v8Sample.copy(team0 = v8Sample.team0.copy(players = v8Sample.team0.players.updated(3, bigPenalty)))
      ) shouldBe Left(OutOfRange(8, "team0.players[3].penalty", 300L, 0L, 255L))
      // Version 7 carries penalties as u16, so the same value fits there.
      GameControllerCodec.encodeControl(
        v7Sample.copy(team0 = v7Sample.team0.copy(players = v7Sample.team0.players.updated(3, bigPenalty)))
      ) should matchPattern { case Right(_) => }
    }
    "refuse player lists and coach messages of the wrong length" in {
      GameControllerCodec.encodeControl(v8Sample.copy(team0 = v8Sample.team0.copy(players = Vector.empty))) shouldBe
        Left(WrongLength("team0.players", 11, 0))
      GameControllerCodec.encodeControl(
        v8Sample.copy(team1 = v8Sample.team1.copy(coachMessage = Some(ArraySeq.fill[Byte](39)(0))))
      ) shouldBe Left(WrongLength("team1.coachMessage", 40, 39))
    }
  }

  "GameControllerCodec return packets" should {
    "encode team, player and message after RGrt and version 2" in {
      GameControllerCodec.encodeReturn(ReturnData(12, 3, ReturnMessage.Alive)).map(_.toSeq) shouldBe
        Right(seq('R', 'G', 'r', 't', 2, 12, 3, 2))
      GameControllerCodec.decodeReturn(ascii("RGrt") ++ bytesOf(2, 7, 1, 0)) shouldBe
        Right(ReturnData(7, 1, ReturnMessage.ManualPenalise))
      GameControllerCodec.decodeReturn(ascii("RGrt") ++ bytesOf(2, 7, 1, 1)) shouldBe
        Right(ReturnData(7, 1, ReturnMessage.ManualUnpenalise))
    }
    "round-trip every valid return packet through exactly 8 bytes" in {
      forAll(returnData) { data =>
        val bytes = GameControllerCodec.encodeReturn(data).fold(err => fail(err.describe), identity)
        bytes.length shouldBe 8
        GameControllerCodec.decodeReturn(bytes) shouldBe Right(data)
      }
    }
    "keep unknown messages as Unknown" in {
      GameControllerCodec.decodeReturn(ascii("RGrt") ++ bytesOf(2, 7, 1, 9)) shouldBe
        Right(ReturnData(7, 1, ReturnMessage.Unknown(9)))
    }
    "refuse every size but 8" in {
      (5 to 300).filter(_ != 8).foreach { n =>
        val bytes = java.util.Arrays.copyOf(ascii("RGrt") ++ bytesOf(2, 7, 1, 2), n)
        GameControllerCodec.decodeReturn(bytes) shouldBe Left(WrongSize("RGrt", 2, 8, n))
      }
      GameControllerCodec.decodeReturn(ascii("RGrt")) shouldBe Left(TooShort(5, 4))
      GameControllerCodec.decodeReturn(ascii("RGr")) shouldBe Left(TooShort(4, 3))
    }
    "refuse unknown versions and wrong headers" in {
      forAll(Gen.choose(0, 255).filter(_ != 2)) { version =>
        GameControllerCodec.decodeReturn(ascii("RGrt") ++ bytesOf(version, 7, 1, 2)) shouldBe
          Left(UnknownVersion("RGrt", seq(version)))
      }
      GameControllerCodec.decodeReturn(ascii("RGme") ++ bytesOf(2, 7, 1, 2)) shouldBe
        Left(WrongHeader("RGrt", seq('R', 'G', 'm', 'e')))
    }
    "refuse numbers that do not fit a byte" in {
      GameControllerCodec.encodeReturn(ReturnData(256, 1, ReturnMessage.Alive)) shouldBe
        Left(OutOfRange(2, "team", 256L, 0L, 255L))
      GameControllerCodec.encodeReturn(ReturnData(1, -1, ReturnMessage.Alive)) shouldBe
        Left(OutOfRange(2, "player", -1L, 0L, 255L))
      GameControllerCodec.encodeReturn(ReturnData(1, 1, ReturnMessage.Unknown(1000))) shouldBe
        Left(OutOfRange(2, "message", 1000L, 0L, 255L))
    }
    "never throw, for arbitrary bytes" in {
      forAll(bytes(400)) { bytes =>
        noException should be thrownBy GameControllerCodec.decodeReturn(bytes)
      }
    }
  }

  "The code enumerations" should {
    "map every known code back to its value and every other code to Unknown" in {
      def check[A](known: Seq[A], code: A => Int, fromCode: Int => A, unknown: Int => A): Unit = {
        known.foreach(k => fromCode(code(k)) shouldBe k)
        known.map(code).distinct should have size known.size.toLong
        (0 to 0xffff).filterNot(known.map(code).contains).foreach(c => fromCode(c) shouldBe unknown(c))
      }
      check[GameState](GameState.known, _.code, GameState.fromCode, GameState.Unknown(_))
      check[SecondaryGameState](
        SecondaryGameState.known,
        _.code,
        SecondaryGameState.fromCode,
        SecondaryGameState.Unknown(_)
      )
      check[TeamColour](TeamColour.known, _.code, TeamColour.fromCode, TeamColour.Unknown(_))
      check[KickOffTeam](KickOffTeam.known, _.code, KickOffTeam.fromCode, KickOffTeam.Unknown(_))
      check[GoalColour](GoalColour.known, _.code, GoalColour.fromCode, GoalColour.Unknown(_))
      check[Penalty](Penalty.known, _.code, Penalty.fromCode, Penalty.Unknown(_))
      check[ReturnMessage](ReturnMessage.known, _.code, ReturnMessage.fromCode, ReturnMessage.Unknown(_))
      GameState.known.map(_.code) shouldBe Seq(0, 1, 2, 3, 4)
    }
  }
}
