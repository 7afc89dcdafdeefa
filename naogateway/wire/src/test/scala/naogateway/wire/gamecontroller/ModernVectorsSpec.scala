package naogateway.wire.gamecontroller

import scala.collection.immutable.ArraySeq

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** The version-19 and version-12 packets in the test resources' `vectors/gamecontroller/` (built from the official
  * layouts by the folder's own script), decoded field by field against their README, and encoded back byte-exact.
  */
class ModernVectorsSpec extends AnyWordSpec with Matchers {
  import ModernVectorsSpec._

  private def decoded(file: String): GameControlData =
    GameControllerCodec.decodeControl(GameControllerVectors.bytes(file)).fold(err => fail(s"$file: ${err.describe}"),
      identity)

  private def v19(file: String): HslControlData = decoded(file) match {
    case d: HslControlData => d
    case other             => fail(s"$file is not version 19: $other")
  }

  private def v12(file: String): HlControlData = decoded(file) match {
    case d: HlControlData => d
    case other            => fail(s"$file is not version 12: $other")
  }

  private val substitutesV19 = Vector.fill(13)(HslPlayerInfo(HslPenalty.Substitute, 0, 0, 0))

  private def hslTeam(number: Int, colour: FieldColour, keeperColour: FieldColour, score: Int, budget: Int) =
    HslTeamInfo(number, colour, keeperColour, 1, score, 0, 0, budget,
      Vector.fill(7)(HslPlayerInfo.Unpenalised) ++ substitutesV19)

  private def hsl(packet: Int, state: GameState) = HslControlData(
    packet,
    7,
    CompetitionType.Small,
    stopped = false,
    GamePhase.Normal,
    state,
    SetPlay.NoSetPlay,
    firstHalf = true,
    Some(12),
    600L,
    0,
    hslTeam(12, FieldColour.Blue, FieldColour.Yellow, 0, 12000),
    hslTeam(7, FieldColour.Red, FieldColour.Black, 0, 12000)
  )

  private def withBudget(d: HslControlData, b0: Int, b1: Int, s0: Int = 0, s1: Int = 0) =
    d.copy(team0 = d.team0.copy(messageBudget = b0, score = s0), team1 = d.team1.copy(messageBudget = b1, score = s1))

  private val expectedV19: Map[String, HslControlData] = {
    val playing =
      withBudget(hsl(4, GameState.Playing), 11800, 11790, 2, 1).copy(stopped = true, setPlay = SetPlay.GoalKick,
        kickingTeam = Some(7), secsRemaining = 587L, secondaryTime = 30)
    Map(
      "v19-initial.bin" -> hsl(1, GameState.Initial),
      "v19-ready.bin" -> hsl(2, GameState.Ready).copy(secondaryTime = 45),
      "v19-set.bin" -> withBudget(hsl(3, GameState.Set), 11950, 11940),
      "v19-playing.bin" -> playing.copy(team0 = playing.team0.copy(players =
        playing.team0.players.updated(2, HslPlayerInfo(HslPenalty.Pushing, 25, 1, 1)))),
      "v19-finished.bin" -> withBudget(hsl(5, GameState.Finished), 11000, 10990, 2, 1).copy(firstHalf = false,
        kickingTeam = Some(7), secsRemaining = 0L)
    )
  }

  private val keeper = HlPlayerInfo.Unpenalised.copy(goalkeeper = true)
  private val hlPlayers = Vector(keeper) ++ Vector.fill(3)(HlPlayerInfo.Unpenalised) ++
    Vector.fill(7)(HlPlayerInfo.Unpenalised.copy(penalty = HlPenalty.Substitute))

  private def hlTeam(number: Int, colour: FieldColour, score: Int) = HlTeamInfo(number, colour, score, 0, 0, 0,
    ArraySeq.fill[Byte](HlPlayerInfo.CoachMessageBytes)(0), HlPlayerInfo.Unpenalised, hlPlayers)

  private val noInfo = ArraySeq[Byte](0, 0, 0, 0)

  private def hl(packet: Int, state: GameState) = HlControlData(
    packet,
    4,
    HlGameType.KidSize,
    state,
    firstHalf = true,
    Some(12),
    HlSecondaryState.Normal,
    noInfo,
    0,
    0xffff,
    600L,
    0,
    hlTeam(12, FieldColour.Blue, 0),
    hlTeam(7, FieldColour.Red, 0)
  )

  private val expectedV12: Map[String, HlControlData] = {
    val playing = hl(4, GameState.Playing).copy(
      kickOffTeam = Some(7),
      secondaryState = HlSecondaryState.DirectFreeKick,
      secondaryStateInfo = ArraySeq[Byte](7, 0, 0, 0),
      secsRemaining = 587L,
      team0 = hlTeam(12, FieldColour.Blue, 2),
      team1 = hlTeam(7, FieldColour.Red, 1)
    )
    Map(
      "v12-initial.bin" -> hl(1, GameState.Initial),
      "v12-ready.bin" -> hl(2, GameState.Ready).copy(secondaryTime = 30),
      "v12-set.bin" -> hl(3, GameState.Set),
      "v12-playing.bin" -> playing.copy(team0 = playing.team0.copy(players =
        playing.team0.players.updated(2, HlPlayerInfo(HlPenalty.PhysicalContact, 25, 1, 1, 0, goalkeeper = false)))),
      "v12-finished.bin" -> hl(5, GameState.Finished).copy(firstHalf = false, kickOffTeam = Some(7), secsRemaining = 0L,
        team0 = hlTeam(12, FieldColour.Blue, 2), team1 = hlTeam(7, FieldColour.Red, 1))
    )
  }

  "The expectations" should {
    "cover exactly the built vectors" in {
      (expectedV19.keySet ++ expectedV12.keySet) shouldBe files.toSet
    }
  }

  expectedV19.toSeq.sortBy(_._1).foreach { case (file, expected) =>
    s"The vector $file" should {
      "be a 198-byte RGme packet of version 19" in {
        val bytes = GameControllerVectors.bytes(file)
        bytes.length shouldBe 198
        new String(bytes.take(4), "US-ASCII") shouldBe "RGme"
        bytes(4) shouldBe 19.toByte
      }
      "decode to the values its README lists" in {
        v19(file) shouldBe expected
      }
      "encode back to the identical bytes" in {
        GameControllerCodec.encodeControl(v19(file)).map(_.toSeq) shouldBe Right(
          GameControllerVectors.bytes(file).toSeq)
        GameControllerCodec.encodeControl(expected).map(_.toSeq) shouldBe Right(GameControllerVectors.bytes(file).toSeq)
      }
    }
  }

  expectedV12.toSeq.sortBy(_._1).foreach { case (file, expected) =>
    s"The vector $file" should {
      "be a 688-byte RGme packet of version 12 as a u16" in {
        val bytes = GameControllerVectors.bytes(file)
        bytes.length shouldBe 688
        new String(bytes.take(4), "US-ASCII") shouldBe "RGme"
        bytes.slice(4, 6).toSeq shouldBe Seq[Byte](12, 0)
      }
      "decode to the values its README lists" in {
        v12(file) shouldBe expected
      }
      "encode back to the identical bytes" in {
        GameControllerCodec.encodeControl(expected).map(_.toSeq) shouldBe Right(GameControllerVectors.bytes(file).toSeq)
      }
    }
  }
}

/** The built vectors' names, as the README lists them. */
object ModernVectorsSpec {

  /** Every built vector, one per state and version. */
  val files: Seq[String] = for {
    version <- Seq(19, 12)
    state <- Seq("initial", "ready", "set", "playing", "finished")
  } yield s"v$version-$state.bin"
}
