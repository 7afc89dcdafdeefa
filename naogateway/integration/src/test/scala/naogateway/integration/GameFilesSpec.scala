package naogateway.integration

import java.nio.file.{Files, Path}

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.api.GameStateUpdated
import naogateway.wire.gamecontroller._
import naogateway.api.recording.Decision
import naogateway.gateway.recording.{GameFiles, McapReader, Recording, RecordingSettings}
import naogateway.testkit.TempFiles.withTempDir

/** One recording file per half of a game: the pure plan, and a recorder following it. */
class GameFilesSpec extends AnyWordSpec with Matchers {
  import GameFiles._

  private val v19: HslControlData =
    GameControllerCodec.decodeControl(GameControllerVectors.bytes("v19-initial.bin")) match {
      case Right(d: HslControlData) => d
      case other                    => fail(s"$other")
    }
  private def at(state: GameState, firstHalf: Boolean = true): GameControlData =
    v19.copy(gameState = state, firstHalf = firstHalf)
  private val s = 1000000000L
  private val first = Half(12, 7, firstHalf = true)
  private val second = Half(12, 7, firstHalf = false)

  /** The steps of a sequence of (packet, seconds) and ticks (None, seconds). */
  private def steps(events: (Option[GameControlData], Long)*): Vector[Step] =
    events.foldLeft((GameFiles(5 * s), Vector.empty[Step])) { case ((plan, done), (packet, secs)) =>
      val (next, more) = packet.fold(plan.tick(secs * s))(plan.packet(_, secs * s))
      (next, done ++ more)
    }._2

  "The plan of game files" should {
    "begin a file at each half's first READY and end it at FINISHED" in {
      steps(
        Some(at(GameState.Initial)) -> 0L,
        Some(at(GameState.Ready)) -> 1L,
        Some(at(GameState.Ready)) -> 2L,
        Some(at(GameState.Set)) -> 3L,
        Some(at(GameState.Playing)) -> 4L,
        Some(at(GameState.Ready)) -> 5L,
        Some(at(GameState.Finished)) -> 6L,
        Some(at(GameState.Initial, firstHalf = false)) -> 7L,
        Some(at(GameState.Ready, firstHalf = false)) -> 8L,
        Some(at(GameState.Finished, firstHalf = false)) -> 9L
      ) shouldBe
        Vector(Begin(first), End("team12-vs-team7-half1 finished"), Begin(second),
          End("team12-vs-team7-half2 finished"))
    }
    "end a half when its GameController goes quiet, and when the next half begins without a FINISHED heard" in {
      steps(Some(at(GameState.Ready)) -> 0L, None -> 4L, Some(at(GameState.Playing)) -> 4L, None -> 8L,
        None -> 9L) shouldBe
        Vector(Begin(first), End("team12-vs-team7-half1: no GameController packet for 5 s"))
      steps(Some(at(GameState.Ready)) -> 0L, Some(at(GameState.Ready, firstHalf = false)) -> 1L) shouldBe
        Vector(Begin(first), End("team12-vs-team7-half1 over: team12-vs-team7-half2 began"), Begin(second))
      steps(Some(at(GameState.Initial)) -> 0L, None -> 60L) shouldBe empty
    }
    "name a file by its teams and half" in {
      fileName("20260101-120000", Some(first), 3) shouldBe "naogateway-20260101-120000-team12-vs-team7-half1-3.mcap"
      fileName("20260101-120000", None, 4) shouldBe "naogateway-20260101-120000-4.mcap"
    }
  }

  "A recorder with game files" should {
    "write each half into a file of its own, named by teams and half, the game's packets in it" in {
      withTempDir("game-files-spec") { dir =>
        val tap = new naogateway.gateway.tap.Tap
        val recording =
          Recording(RecordingSettings(enabled = true, dir, 64L * 1024 * 1024, 10.minutes, 65536, gameFiles = true,
              gameQuiet = 5.seconds), "game-files-spec", tap)
        def publish(d: GameControlData): Unit = {
          tap.decision(Decision.Published(GameStateUpdated(d))); Thread.sleep(20)
        }
        publish(at(GameState.Initial))
        Seq(GameState.Ready, GameState.Set, GameState.Playing, GameState.Finished).foreach(st => publish(at(st)))
        publish(at(GameState.Initial, firstHalf = false))
        Seq(GameState.Ready, GameState.Playing, GameState.Finished).foreach(st => publish(at(st, firstHalf = false)))
        recording.close()
        val names = Files.list(dir).iterator().asScala.map(_.getFileName.toString).toVector.sorted
        names.map(_.replaceAll("^naogateway-\\d{8}-\\d{6}", "T"))
          .sortBy(_.stripSuffix(".mcap").split('-').last.toInt) shouldBe
          Vector("T-1.mcap", "T-team12-vs-team7-half1-2.mcap", "T-3.mcap", "T-team12-vs-team7-half2-4.mcap")
        def states(name: String): Vector[String] = {
          val path: Path = dir.resolve(names.find(_.contains(name)).get)
          McapReader.read(Files.readAllBytes(path)).messages.map(m => new String(m.data, "UTF-8"))
            .flatMap("\"state\":\"(\\w+)\"".r.findFirstMatchIn(_).map(_.group(1)))
        }
        states("half1") shouldBe Vector("Ready", "Set", "Playing", "Finished")
        states("half2") shouldBe Vector("Ready", "Playing", "Finished")
      }
    }
  }
}
