package naogateway.wire.gamecontroller

import java.nio.charset.StandardCharsets
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** The 2014 packets in the test resources' `vectors/gamecontroller/`, checked against their README. */
class GameControllerVectorsSpec extends AnyWordSpec with Matchers {
  import GameControllerVectorsSpec.Expected

  private def vector(file: String): Array[Byte] = GameControllerVectors.bytes(file)

  private val v8PlayingPenalty = Some((0, 2, Penalty.BallManipulation, 25))

  // The README states kickOffTeam, score and secondaryTime only where they are not 0; the other rows
  // expect the 0 the packets carry (kick-off blue, score 0 : 0, secondaryTime 0).
  private val table = List(
    Expected("v8-initial.bin", GameControlVersion.V8, Some(1), GameState.Initial, secondaryTime = Some(0)),
    Expected("v7-initial.bin", GameControlVersion.V7, None, GameState.Initial, secondaryTime = None),
    Expected("v8-ready.bin", GameControlVersion.V8, Some(2), GameState.Ready, secondaryTime = Some(30)),
    Expected("v8-set.bin", GameControlVersion.V8, Some(3), GameState.Set, secondaryTime = Some(0)),
    Expected(
      "v8-playing.bin",
      GameControlVersion.V8,
      Some(4),
      GameState.Playing,
      kickOffTeam = KickOffTeam.Red,
      secsRemaining = 587L,
      secondaryTime = Some(0),
      score = (2, 1),
      penalised = v8PlayingPenalty
    ),
    Expected(
      "v7-playing.bin",
      GameControlVersion.V7,
      None,
      GameState.Playing,
      kickOffTeam = KickOffTeam.Red,
      secsRemaining = 587L,
      secondaryTime = None,
      score = (2, 1),
      penalised = v8PlayingPenalty
    ),
    Expected(
      "v8-finished.bin",
      GameControlVersion.V8,
      Some(5),
      GameState.Finished,
      firstHalf = false,
      kickOffTeam = KickOffTeam.Red,
      secsRemaining = 587L,
      secondaryTime = Some(0),
      score = (2, 1),
      penalised = v8PlayingPenalty
    )
  )

  "The GameController vector folder" should {
    "hold exactly the files the README lists" in {
      val listed =
        raw"(?m)^\| (v\d+-[a-z-]+\.bin) \|".r.findAllMatchIn(GameControllerVectors.readme).map(_.group(1)).toList
      listed.sorted shouldBe (table.map(_.file) ++ ModernVectorsSpec.files ++ Version20CodecSpec.files).sorted
      listed.foreach(file => vector(file) should not be empty)
    }
  }

  table.foreach { e =>
    s"The vector ${e.file}" should {
      "have the header RGme and the size of its version" in {
        val bytes = vector(e.file)
        new String(bytes.take(4), StandardCharsets.US_ASCII) shouldBe "RGme"
        bytes.length shouldBe e.version.packetBytes
      }

      "decode to the values its README lists" in {
        val data = GameControllerCodec.decodeControl(vector(e.file)) match {
          case Right(d: ControlData2014) => d
          case other                     => fail(s"not a 2014 packet: $other")
        }
        data.version shouldBe e.version
        data.packetNumber shouldBe e.packetNumber
        data.playersPerTeam shouldBe 6
        data.gameState shouldBe e.gameState
        data.firstHalf shouldBe e.firstHalf
        data.kickOffTeam shouldBe e.kickOffTeam
        data.secondaryGameState shouldBe SecondaryGameState.Normal
        data.dropInTeam shouldBe TeamColour.Blue
        data.dropInTime shouldBe -1
        data.secsRemaining shouldBe e.secsRemaining
        data.secondaryTime shouldBe e.secondaryTime

        data.team0.teamNumber shouldBe 12
        data.team0.teamColour shouldBe TeamColour.Blue
        data.team0.score shouldBe e.score._1
        data.team1.teamNumber shouldBe 7
        data.team1.teamColour shouldBe TeamColour.Red
        data.team1.score shouldBe e.score._2

        val slots = for {
          (team, t) <- List(data.team0, data.team1).zipWithIndex
          (player, p) <- team.players.zipWithIndex
        } yield ((t, p), player)
        slots should have size (2L * TeamInfo.PlayerSlots)
        val expectedPenalised = e.penalised.map { case (t, p, penalty, secs) => (t, p) -> PlayerInfo(penalty, secs) }
        expectedPenalised.foreach { case (slot, player) => slots.toMap.apply(slot) shouldBe player }
        val others = slots.filterNot { case (slot, _) => expectedPenalised.exists(_._1 == slot) }
        all(others.map(_._2)) shouldBe PlayerInfo.Unpenalised
      }

      "encode back to the identical bytes" in {
        val bytes = vector(e.file)
        val data = GameControllerCodec.decodeControl(bytes).fold(err => fail(err.describe), identity)
        GameControllerCodec.encodeControl(data).map(_.toSeq) shouldBe Right(bytes.toSeq)
      }
    }
  }
}

object GameControllerVectorsSpec {

  /** One row of the README's table; `penalised` is (team index, player index, penalty, secsTillUnpenalised). */
  final case class Expected(
      file: String,
      version: GameControlVersion,
      packetNumber: Option[Int],
      gameState: GameState,
      firstHalf: Boolean = true,
      kickOffTeam: KickOffTeam = KickOffTeam.Blue,
      secsRemaining: Long = 600L,
      secondaryTime: Option[Int],
      score: (Int, Int) = (0, 0),
      penalised: Option[(Int, Int, Penalty, Int)] = None
  )
}
