package naogateway.wire.gamecontroller

import java.nio.charset.StandardCharsets

import scala.collection.immutable.ArraySeq

import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.wire.gamecontroller.GameControllerError._

/** Version 20 of the control packet (the Humanoid Soccer League's GameController 7, RoboCup 2026): the built vectors of
  * `vectors/gamecontroller/` against their README, byte-exact round trips, refusals, `RGTD`, and the reading of an
  * unknown later version by its shared header (docs/protocol.md §10.2, §10.8).
  */
class Version20CodecSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {
  import GameControllerGenerators._

  implicit override val generatorDrivenConfig: PropertyCheckConfiguration =
    PropertyCheckConfiguration(minSuccessful = 200)

  private def ascii(s: String): Array[Byte] = s.getBytes(StandardCharsets.US_ASCII)
  private def seq(values: Int*): ArraySeq[Byte] = ArraySeq.from(values.map(_.toByte))

  private def v20(file: String): Hsl20ControlData =
    GameControllerCodec.decodeControl(GameControllerVectors.bytes(file)) match {
      case Right(d: Hsl20ControlData) => d
      case other                      => fail(s"$file is not a readable version-20 packet: $other")
    }

  private val substitutes = Vector.fill(13)(Hsl20PlayerInfo(Hsl20Penalty.Substitute, 0, 0))

  private def team(number: Int, colour: FieldColour, keeperColour: FieldColour) =
    Hsl20TeamInfo(number, colour, keeperColour, 1, 0, 0, 0, 12000,
      Vector.fill(7)(Hsl20PlayerInfo.Unpenalised) ++
        substitutes)

  private val base = Hsl20ControlData(
    1,
    7,
    CompetitionType.Small,
    stopped = false,
    GamePhase.Normal,
    GameState.Initial,
    SetPlay.NoSetPlay,
    firstHalf = true,
    Some(12),
    600L,
    0,
    team(12, FieldColour.Blue, FieldColour.Yellow),
    team(7, FieldColour.Red, FieldColour.Black)
  )

  private def scoreAndBudget(d: Hsl20ControlData, b0: Int, b1: Int): Hsl20ControlData =
    d.copy(team0 = d.team0.copy(score = 2, messageBudget = b0), team1 = d.team1.copy(score = 1, messageBudget = b1))

  /** The README's table, one half at a time. */
  private def expected(state: GameState, firstHalf: Boolean): Hsl20ControlData = {
    val half = base.copy(packetNumber = state.code + (if (firstHalf) 1 else 11), gameState = state,
      firstHalf = firstHalf, kickingTeam = Some(if (firstHalf) 12 else 7))
    state match {
      case GameState.Ready => half.copy(secondaryTime = 45)
      case GameState.Playing =>
        val p = scoreAndBudget(half, 11800, 11790).copy(stopped = true, setPlay = SetPlay.GoalKick,
          kickingTeam = Some(7), secsRemaining = 587L, secondaryTime = 30)
        p.copy(team0 = p.team0.copy(players = p.team0.players.updated(2, Hsl20PlayerInfo(Hsl20Penalty.Pushing, 25, 0))))
      case GameState.Finished => scoreAndBudget(half, 11000, 10990).copy(secsRemaining = 0L)
      case _                  => half
    }
  }

  private val states = Version20CodecSpec.states

  for {
    state <- states
    firstHalf <- Seq(true, false)
  } {
    val file = s"v20-${state.toString.toLowerCase}${if (firstHalf) "" else "-second-half"}.bin"
    s"The vector $file" should {
      "be a 158-byte RGme packet of version 20" in {
        val bytes = GameControllerVectors.bytes(file)
        bytes.length shouldBe 158
        new String(bytes.take(4), "US-ASCII") shouldBe "RGme"
        bytes(4) shouldBe 20.toByte
      }
      "decode to the values its README lists, and encode back to the identical bytes" in {
        v20(file) shouldBe expected(state, firstHalf)
        GameControllerCodec.encodeControl(expected(state, firstHalf)).map(_.toSeq) shouldBe
          Right(GameControllerVectors.bytes(file).toSeq)
      }
    }
  }

  "The vector v20-penalties.bin" should {
    "carry every version-20 penalty by name, motion in stop (3) and cautioned (11) among them" in {
      val players = v20("v20-penalties.bin").team0.players
      players.take(14).map(_.penalty) shouldBe Hsl20Penalty.known
      players.take(14).map(_.penalty.code) shouldBe (0 to 13)
      players(3).penalty shouldBe Hsl20Penalty.MotionInStop
      players(11) shouldBe Hsl20PlayerInfo(Hsl20Penalty.Cautioned, 21, 1)
      players(12) shouldBe Hsl20PlayerInfo(Hsl20Penalty.SentOff, 0, 0)
      players(13) shouldBe Hsl20PlayerInfo(Hsl20Penalty.Substitute, 0, 0)
      players.take(14).map(_.secsTillUnpenalised) shouldBe (0 +: (1 to 11).map(10 + _)) ++ Seq(0, 0)
      players.take(14).forall(p => p.penalty.isPenalised == (p.penalty.code != 0)) shouldBe true
      Hsl20Penalty.known.exists(_.isInstanceOf[Hsl20Penalty.Unknown]) shouldBe false
    }
    "encode back to the identical bytes" in {
      GameControllerCodec.encodeControl(v20("v20-penalties.bin")).map(_.toSeq) shouldBe
        Right(GameControllerVectors.bytes("v20-penalties.bin").toSeq)
    }
  }

  "Version 20" should {
    "round-trip every valid value through exactly 158 bytes with a u8 version" in {
      forAll(controlV20) { data =>
        val bytes = GameControllerCodec.encodeControl(data).fold(e => fail(e.describe), identity)
        bytes.length shouldBe 158
        bytes(4) shouldBe 20.toByte
        GameControllerCodec.decodeControl(bytes) shouldBe Right(data)
      }
    }
    "give back the identical bytes for every packet it accepts" in {
      val packets = for {
        tail <- Gen.containerOfN[Array, Byte](153, Gen.choose(Byte.MinValue, Byte.MaxValue))
        stopped <- Gen.oneOf(0, 1)
        half <- Gen.oneOf(0, 1)
      } yield {
        val bytes = ascii("RGme") ++ Array(20.toByte) ++ tail
        bytes(8) = stopped.toByte
        bytes(12) = half.toByte
        bytes
      }
      forAll(packets) { bytes =>
        val data = GameControllerCodec.decodeControl(bytes).fold(err => fail(err.describe), identity)
        data shouldBe a[Hsl20ControlData]
        GameControllerCodec.encodeControl(data).map(_.toSeq) shouldBe Right(bytes.toSeq)
      }
    }
    "refuse every size but 158, and version 19's size" in {
      val sample = GameControllerVectors.bytes("v20-playing.bin")
      (5 to 800).filter(_ != 158).foreach { n =>
        GameControllerCodec.decodeControl(java.util.Arrays.copyOf(sample, n)) shouldBe
          Left(WrongSize("RGme", 20, 158, n))
      }
    }
    "refuse stopped and firstHalf bytes other than 0 or 1, and players lists of the wrong length" in {
      val sample = GameControllerVectors.bytes("v20-playing.bin")
      GameControllerCodec.decodeControl(sample.updated(8, 2.toByte)) shouldBe Left(InvalidField("stopped", 2L))
      GameControllerCodec.decodeControl(sample.updated(12, 7.toByte)) shouldBe Left(InvalidField("firstHalf", 7L))
      val d = controlV20.sample.get
      GameControllerCodec.encodeControl(d.copy(team0 = d.team0.copy(players = d.team0.players.take(11)))) shouldBe
        Left(WrongLength("team0.players", 20, 11))
      GameControllerCodec.encodeControl(d.copy(team1 = d.team1.copy(messageBudget = 70000))) shouldBe
        Left(OutOfRange(20, "team1.messageBudget", 70000L, 0L, 65535L))
    }
    "share its first 18 bytes with version 19: the same header fields read the same" in {
      forAll(controlV20) { d =>
        val bytes = GameControllerCodec.encodeControl(d).toOption.get
        val header = GameControllerCodec.decodeSharedHeader(bytes.updated(4, 21.toByte))
        if (d.gameState.isInstanceOf[GameState.Unknown])
          header shouldBe Left(InvalidField("state", d.gameState.code.toLong))
        else
          header.map(h => (h.gameState, h.stopped, h.setPlay, h.firstHalf, h.secsRemaining, h.packetNumber)) shouldBe
            Right((d.gameState, d.stopped, d.setPlay, d.firstHalf, d.secsRemaining, d.packetNumber))
      }
    }
    "come under RGTD for a monitor" in {
      forAll(controlV20) { data =>
        val bytes = GameControllerCodec.encodeTrueData(data).fold(err => fail(err.describe), identity)
        bytes.take(4).toSeq shouldBe ascii("RGTD").toSeq
        bytes.length shouldBe 158
        GameControllerCodec.decodeTrueData(bytes) shouldBe Right(data)
      }
    }
  }

  "An RGme packet of a version not known" should {
    val playing = GameControllerVectors.bytes("v20-playing.bin")
    "be read by its shared header when its version is 18 or above 20 and its size plausible" in {
      Seq(18, 21, 22, 99, 255).foreach { version =>
        Seq(38, 158, 170, 198, 1024).foreach { size =>
          val bytes = java.util.Arrays.copyOf(playing.updated(4, version.toByte), size)
          val h = GameControllerCodec.decodeSharedHeader(bytes).fold(e => fail(e.describe), identity)
          (h.versionNumber, h.packetBytes, h.gameState, h.stopped, h.setPlay, h.firstHalf, h.secsRemaining) shouldBe
            ((version, size, GameState.Playing, true, SetPlay.GoalKick, true, 587L))
        }
      }
      GameControllerCodec.decodeControl(playing.updated(4, 21.toByte)) shouldBe Left(UnknownVersion("RGme",
          seq(21, 4, 7, 0)))
    }
    "be refused when its size is implausible, its version older or known, its state unknown or its flags not 0 or 1" in {
      Seq(5, 18, 37, 1025, 1400).foreach { size =>
        GameControllerCodec.decodeSharedHeader(java.util.Arrays.copyOf(playing.updated(4, 21.toByte), size)) shouldBe
          Left(ImplausibleSize("RGme", 21, 38, 1024, size))
      }
      Seq(7, 8, 12, 14, 17, 19, 20).foreach { version =>
        GameControllerCodec.decodeSharedHeader(playing.updated(4, version.toByte)) shouldBe
          Left(UnknownVersion("RGme", seq(version)))
      }
      GameControllerCodec.decodeSharedHeader(playing.updated(4, 21.toByte).updated(10, 9.toByte)) shouldBe
        Left(InvalidField("state", 9L))
      GameControllerCodec.decodeSharedHeader(playing.updated(4, 21.toByte).updated(8, 2.toByte)) shouldBe
        Left(InvalidField("stopped", 2L))
      GameControllerCodec.decodeSharedHeader(ascii("RGTD") ++ playing.drop(4).updated(0, 21.toByte)) shouldBe
        Left(WrongHeader("RGme", seq('R', 'G', 'T', 'D')))
    }
  }
}

/** The version-20 vectors' names, as the README lists them. */
object Version20CodecSpec {

  /** The states, one vector per half each. */
  val states: Seq[GameState] =
    Seq(GameState.Initial, GameState.Ready, GameState.Set, GameState.Playing, GameState.Finished)

  /** Every version-20 vector: each state in both halves, and every penalty. */
  val files: Seq[String] = states.flatMap { s =>
    val name = s.toString.toLowerCase
    Seq(s"v20-$name.bin", s"v20-$name-second-half.bin")
  } :+ "v20-penalties.bin"
}
