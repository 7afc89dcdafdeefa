package naogateway.gateway.gamecontroller

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.wire.gamecontroller.{GameControlVersion, GameState}
import naogateway.api.GameReading

/** The competition rule (docs/protocol.md 10.7) without actors: which readings close the gate, and the latch that
  * closes it fast and opens it slowly.
  */
class CompetitionGateSpec extends AnyWordSpec with Matchers {

  private val running = Set[GameState](GameState.Ready, GameState.Set, GameState.Playing)
  private val states = GameState.known ++ Seq(GameState.Unknown(5), GameState.Unknown(255))
  private val ms = 1000000L
  private val openAfter = 3000 * ms

  private def said(state: GameState) = GateLatch.known(state, GameControlVersion.V20)

  /** The latch after `packets` of (state, packet number, time in ms). */
  private def after(start: GateLatch, packets: (GameState, Int, Long)*): GateLatch =
    packets.foldLeft(start) { case (l, (s, n, t)) => l.packet(said(s), Some(n), t * ms) }

  private val closedInPlaying = after(GateLatch.start(competition = true, openAfter), (GameState.Playing, 1, 0L))

  "The competition gate" should {
    "close in READY, SET and PLAYING of every version and of a shared header, and stay open in every other state" in {
      for {
        version <- GameControlVersion.all
        state <- states
      } {
        val reading = GameReading.Known(state, Some(version))
        CompetitionGate.closes(reading) shouldBe running(state)
        CompetitionGate.why(reading).isDefined shouldBe running(state)
        CompetitionGate.closes(GameReading.HeaderOnly(state, 21, 170)) shouldBe running(state)
      }
    }
    "stay closed on an unreadable packet, while it waits to open, and before anything is heard, saying why" in {
      val reading = GameReading.Unreadable("RGme of unknown version 9, 40 bytes; 3 so far")
      CompetitionGate.closes(reading) shouldBe true
      CompetitionGate.why(reading) shouldBe
        Some("the trusted GameController's packet cannot be read (RGme of unknown version 9, 40 bytes; 3 so far)")
      CompetitionGate.closes(GameReading.Opening(GameState.Initial, 1200L, 2L)) shouldBe true
      CompetitionGate.why(GameReading.Opening(GameState.Initial, 1200L, 2L)) shouldBe
        Some("opening once the game has not run for a while (Initial, 2 s more, 2 contradiction(s) so far)")
      CompetitionGate.closes(GameReading.NotHeard) shouldBe true
      CompetitionGate.closes(GameReading.Nothing) shouldBe false
    }
    "tell packet numbers that follow one another, a few lost between, wrapping at 256" in {
      CompetitionGate.follows(4, 5) shouldBe true
      CompetitionGate.follows(4, 8) shouldBe true
      CompetitionGate.follows(4, 9) shouldBe false
      CompetitionGate.follows(4, 4) shouldBe false
      CompetitionGate.follows(4, 3) shouldBe false
      CompetitionGate.follows(255, 0) shouldBe true
      CompetitionGate.follows(254, 1) shouldBe true
    }
  }

  "The gate latch" should {
    "start closed in competition mode and open otherwise" in {
      GateLatch.start(competition = true, openAfter).open shouldBe false
      GateLatch.start(competition = true, openAfter).reading shouldBe GameReading.NotHeard
      GateLatch.start(competition = false, openAfter).open shouldBe true
    }
    "close at once on a packet saying the game runs, whatever came before" in {
      running.foreach { s =>
        after(GateLatch.start(competition = false, openAfter), (s, 1, 0L)).open shouldBe false
        after(closedInPlaying, (GameState.Initial, 2, 500L), (GameState.Initial, 3, 1000L), (s, 4, 1500L))
          .open shouldBe false
      }
    }
    "open only once every packet for the whole time said the game does not run, in sequence" in {
      val waiting = after(
        closedInPlaying,
        (GameState.Initial, 2, 500L),
        (GameState.Initial, 3, 1000L),
        (GameState.Initial, 4, 1500L),
        (GameState.Initial, 5, 2000L),
        (GameState.Initial, 6, 3000L)
      )
      waiting.open shouldBe false
      waiting.reading shouldBe GameReading.Opening(GameState.Initial, 500L, 0L)
      val opened = after(waiting, (GameState.Initial, 7, 3500L))
      opened.open shouldBe true
      opened.reading shouldBe said(GameState.Initial)
      opened.contradictions shouldBe 0L
      // FINISHED opens it the same way, and once open, more such packets keep it open.
      after(closedInPlaying, (GameState.Finished, 2, 500L), (GameState.Finished, 3, 3500L)).open shouldBe true
      after(opened, (GameState.Initial, 8, 4000L), (GameState.Finished, 200, 4500L)).open shouldBe true
    }
    "stay closed while forged INITIAL packets come between the real PLAYING ones, counting each contradiction" in {
      // The real GameController: PLAYING every 500 ms, numbered 2, 3, ...; the forger: INITIAL in between, with
      // the numbers it guesses right.
      val packets = (1 to 40).flatMap { i =>
        Seq((GameState.Initial, 2 * i, 500L * i - 250L), (GameState.Playing, 2 * i + 1, 500L * i))
      }
      val trace = packets.scanLeft(closedInPlaying) { case (l, (s, n, t)) => l.packet(said(s), Some(n), t * ms) }
      trace.forall(!_.open) shouldBe true
      trace.last.contradictions shouldBe 40L
      CompetitionGate.why(trace.last.reading) shouldBe Some("the game is running (Playing)")
    }
    "restart the wait on a packet number out of sequence or an unreadable packet, counting it" in {
      val jumped = after(closedInPlaying, (GameState.Initial, 2, 500L), (GameState.Initial, 60, 1000L),
        (GameState.Initial, 61, 3900L))
      jumped.open shouldBe false
      jumped.contradictions shouldBe 1L
      after(jumped, (GameState.Initial, 62, 4000L)).open shouldBe true
      val unread = after(closedInPlaying, (GameState.Initial, 2, 500L)).unreadable("RGme of unknown version 9")
      unread.open shouldBe false
      unread.contradictions shouldBe 1L
      after(unread, (GameState.Initial, 3, 1000L), (GameState.Initial, 4, 3500L)).open shouldBe false
      after(unread, (GameState.Initial, 3, 1000L), (GameState.Initial, 4, 4000L)).open shouldBe true
    }
    "open without packet numbers (version 7) by time alone, and on a shared header's state" in {
      val v7 =
        closedInPlaying.packet(GameReading.Known(GameState.Finished, Some(GameControlVersion.V7)), None, 500 * ms)
      v7.packet(GameReading.Known(GameState.Finished, Some(GameControlVersion.V7)), None, 3500 * ms).open shouldBe true
      val h = closedInPlaying.packet(GameReading.HeaderOnly(GameState.Initial, 21, 170), Some(2), 500 * ms)
      h.packet(GameReading.HeaderOnly(GameState.Initial, 21, 170), Some(3), 3500 * ms).open shouldBe true
      closedInPlaying.packet(GameReading.HeaderOnly(GameState.Set, 21, 170), Some(2), 500 * ms).open shouldBe false
    }
  }
}
