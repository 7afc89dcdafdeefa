package naogateway

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.wire.gamecontroller.{GameControlVersion, GameState}

/** The competition rule as one function: which readings close the gate, and how long an unreadable packet holds it. */
class CompetitionGateSpec extends AnyWordSpec with Matchers {

  private val running = Set[GameState](GameState.Ready, GameState.Set, GameState.Playing)
  private val states = GameState.known ++ Seq(GameState.Unknown(5), GameState.Unknown(255))

  "The competition gate" should {
    "close in READY, SET and PLAYING of every version, and stay open in every other state" in {
      for {
        version <- GameControlVersion.all
        state <- states
      } {
        val reading = GameReading.Known(state, Some(version))
        CompetitionGate.closes(reading) shouldBe running(state)
        CompetitionGate.why(reading).isDefined shouldBe running(state)
      }
    }
    "close on a packet of the trusted GameController it cannot read, and say why" in {
      val reading = GameReading.Unreadable("RGme packet of unknown version: bytes from offset 4 are 14 00 00 00")
      CompetitionGate.closes(reading) shouldBe true
      CompetitionGate.why(reading) shouldBe
        Some(
          "the trusted GameController's packet cannot be read: RGme packet of unknown version: bytes from offset 4 are 14 00 00 00")
      CompetitionGate.closes(GameReading.Nothing) shouldBe false
    }
    "let an unreadable packet outweigh readable ones for the hold time, then follow the readable ones again" in {
      val hold = CompetitionGate.UnreadableHoldNanos
      val unreadable = Some(1000L -> "unknown version")
      CompetitionGate.reading(GameState.Initial, GameControlVersion.V19, unreadable, 1000L) shouldBe
        GameReading.Unreadable("unknown version")
      CompetitionGate.reading(GameState.Initial, GameControlVersion.V19, unreadable, 1000L + hold - 1) shouldBe
        GameReading.Unreadable("unknown version")
      CompetitionGate.reading(GameState.Initial, GameControlVersion.V19, unreadable, 1000L + hold) shouldBe
        GameReading.Known(GameState.Initial, Some(GameControlVersion.V19))
      CompetitionGate.reading(GameState.Set, GameControlVersion.V12, None, 0L) shouldBe
        GameReading.Known(GameState.Set, Some(GameControlVersion.V12))
    }
  }
}
