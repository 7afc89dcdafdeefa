package naogateway.integration

import java.net.InetSocketAddress

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.wire.gamecontroller._
import naogateway.gateway.gamecontroller.{GameControllerSources, MessageBudget, TeamMessageSettings}

/** The team's message budget against sequences counted by hand with the GameController's rules (README "Message
  * Counting", its team_message and add_extra_time actions), and the check for a second GameController.
  */
class MessageBudgetSpec extends AnyWordSpec with Matchers {

  private def hsl: HslControlData =
    GameControllerCodec.decodeControl(GameControllerVectors.bytes("v19-initial.bin")) match {
      case Right(d: HslControlData) => d
      case other                    => fail(s"$other")
    }
  private def hl: HlControlData =
    GameControllerCodec.decodeControl(GameControllerVectors.bytes("v12-initial.bin")) match {
      case Right(d: HlControlData) => d
      case other                   => fail(s"$other")
    }

  private def v19(state: GameState, secs: Long, firstHalf: Boolean = true, phase: GamePhase = GamePhase.Normal,
      ours: Int = 12000): HslControlData =
    hsl.copy(gameState = state, secsRemaining = secs, firstHalf = firstHalf, gamePhase = phase,
      team0 = hsl.team0.copy(messageBudget = ours))

  private val settings = TeamMessageSettings(teamNumber = 12, perGame = 10, perExtraMinute = 3)
  private val s = 1000000000L

  /** `n` messages of `bytes` bytes, one a second from `from` seconds. */
  private def send(b: MessageBudget, n: Int, bytes: Int = 100, from: Long = 0L): MessageBudget =
    (0 until n).foldLeft(b)((acc, i) => acc.message(bytes, (from + i) * s))

  "The message budget" should {
    "count in READY, SET and PLAYING only, and add a minute's messages when the GameController adds a minute" in {
      var b = MessageBudget(settings).game(v19(GameState.Initial, 600))
      b = send(b, 2) // INITIAL: not counted
      (b.remaining, b.counted, b.uncounted) shouldBe ((10, 0, 2))
      b = send(b.game(v19(GameState.Ready, 600)), 3) // 10 - 3
      b = send(b.game(v19(GameState.Set, 600)), 1) // 7 - 1
      b = send(b.game(v19(GameState.Playing, 590)), 4) // 6 - 4
      (b.remaining, b.counted) shouldBe ((2, 8))
      b = b.game(v19(GameState.Ready, 500)) // a goal: READY again, clock stopped
      b = b.game(v19(GameState.Ready, 560)) // "+": a minute more, 3 messages more
      (b.remaining, b.extraMinutes) shouldBe ((5, 1))
      b = b.game(v19(GameState.Ready, 560)) // the same clock again adds nothing
      b = send(b, 5) // 5 - 5 = 0
      (b.remaining, b.illegal) shouldBe ((0, false))
      b = send(b.game(v19(GameState.Set, 560)), 1) // over the budget: illegal
      (b.remaining, b.overBudget, b.illegal, b.counted) shouldBe ((0, 1, true, 14))
      b = b.game(v19(GameState.Playing, 500)).game(v19(GameState.Set, 500)).game(v19(GameState.Set, 560))
      (b.remaining, b.extraMinutes) shouldBe ((0, 2)) // a minute after illegal communication adds nothing
      b = send(b.game(v19(GameState.Finished, 0)), 2) // FINISHED: not counted
      b = b.game(v19(GameState.Initial, 600, firstHalf = false)).game(v19(GameState.Ready, 600, firstHalf = false))
      (b.remaining, b.uncounted, b.counted) shouldBe ((0, 4, 14)) // the second half keeps the game's budget
      b = b.game(v19(GameState.Initial, 600)) // the next game's first half: a fresh budget
      (b.remaining, b.counted, b.overBudget, b.extraMinutes) shouldBe ((10, 0, 0, 0))
    }
    "add the extra time's messages when a drawn game goes into extra time, through timeouts, not for an illegal team" in {
      val withExtra = settings.copy(perExtraTime = 6)
      var b = MessageBudget(withExtra).game(v19(GameState.Playing, 300, firstHalf = false))
      b = send(b, 4) // 10 - 4
      b = b.game(v19(GameState.Finished, 0, firstHalf = false))
      // StartExtraTime: the first extra half follows the second half; the budget grows by 6, it is not a new game's.
      b = b.game(v19(GameState.Initial, 300, phase = GamePhase.ExtraTime))
      (b.remaining, b.counted, b.extraTimeGranted) shouldBe ((12, 4, true))
      b.describe(0L) should include("12 of 16 left, 4 counted")
      // A timeout in extra time hides the phase; ending it grants nothing more.
      b = b.game(v19(GameState.Initial, 300, phase = GamePhase.Timeout))
      b = b.game(v19(GameState.Ready, 300, phase = GamePhase.ExtraTime))
      b = send(b, 2)
      b = b.game(v19(GameState.Playing, 150, firstHalf = false, phase = GamePhase.ExtraTime))
      (b.remaining, b.counted) shouldBe ((10, 6))
      // A new game after extra time starts from the game's budget again.
      b = b.game(v19(GameState.Initial, 600))
      (b.remaining, b.counted, b.extraTimeGranted) shouldBe ((10, 0, false))

      // A team that communicated illegally gets no extra time's messages, as with extra minutes.
      var i = MessageBudget(withExtra).game(v19(GameState.Playing, 300, firstHalf = false))
      i = i.message(600, 0L)
      i.illegal shouldBe true
      i = i.game(v19(GameState.Finished, 0, firstHalf = false)).game(v19(GameState.Initial, 300,
          phase = GamePhase.ExtraTime))
      (i.remaining, i.extraTimeGranted) shouldBe ((9, true))
    }

    "not count in a penalty shoot-out, of version 19 or 12" in {
      var b = MessageBudget(settings).game(v19(GameState.Playing, 0, phase = GamePhase.PenaltyShootOut))
      b = send(b, 7)
      (b.remaining, b.counted, b.uncounted) shouldBe ((10, 0, 7))
      b = send(b.game(v19(GameState.Set, 0, phase = GamePhase.PenaltyShootOut)), 2)
      (b.remaining, b.uncounted) shouldBe ((10, 9))
      b = send(b.game(hl.copy(gameState = GameState.Playing, secondaryState = HlSecondaryState.PenaltyShoot)), 3)
      (b.remaining, b.uncounted) shouldBe ((10, 12))
      // Extra time (not a shoot-out) counts again.
      b = send(b.game(v19(GameState.Playing, 300, phase = GamePhase.ExtraTime)), 2)
      (b.remaining, b.counted) shouldBe ((8, 2))
    }
    "refuse a message over 512 bytes as the GameController does, still taking it from the budget" in {
      var b = MessageBudget(settings).game(v19(GameState.Playing, 600))
      b = b.message(512, 0L)
      b.illegal shouldBe false
      b = b.message(513, s)
      (b.remaining, b.oversize, b.illegal) shouldBe ((8, 1, true))
      b.warnings(2 * s).head should startWith("1 team message(s) over 512 bytes")
      // No minute is added after illegal communication.
      b = b.game(v19(GameState.Ready, 500)).game(v19(GameState.Ready, 560))
      b.remaining shouldBe 8
    }
    "read version 20 as version 19: its budget, its phase (extra time) and its states" in {
      val v20 = GameControllerCodec.decodeControl(GameControllerVectors.bytes("v20-set.bin")) match {
        case Right(d: Hsl20ControlData) => d
        case other                      => fail(s"$other")
      }
      def at(state: GameState, firstHalf: Boolean, phase: GamePhase = GamePhase.Normal) =
        v20.copy(gameState = state, firstHalf = firstHalf, gamePhase = phase,
          team0 = v20.team0.copy(messageBudget = 11900))
      val settingsX = settings.copy(perExtraTime = 6)
      var b = MessageBudget(settingsX).game(at(GameState.Set, firstHalf = true))
      b.counting shouldBe true
      b.reported shouldBe Some(11900)
      b = send(b, 2)
      b.remaining shouldBe 8
      // A drawn second half goes into extra time: version 20 says so as version 19 does.
      b = b.game(at(GameState.Finished, firstHalf = false)).game(at(GameState.Initial, firstHalf = true,
          GamePhase.ExtraTime))
      b.extraTimeGranted shouldBe true
      b.remaining shouldBe 14
      b.game(at(GameState.Playing, firstHalf = true, GamePhase.PenaltyShootOut)).counting shouldBe false
    }
    "warn when the budget would run out before the end of the half at the current rate, and show the GameController's own" in {
      var b = MessageBudget(settings.copy(perGame = 1000)).game(v19(GameState.Playing, 600, ours = 990))
      b = (0 until 60).foldLeft(b)((acc, i) => acc.message(100, i * s / 2)) // 60 messages in 30 s
      b.ratePerSecond(30 * s) shouldBe 1.0 +- 1e-9 // over a 60 s window
      // 940 left, 600 s of the half at 1/s: 600 needed, enough.
      b.warnings(30 * s) shouldBe empty
      b = (0 until 600).foldLeft(b)((acc, i) => acc.message(100, 30 * s + i * s / 20)) // 600 more in 30 s: 11/s
      b.remaining shouldBe 340
      val w = b.warnings(60 * s)
      w should have size 1
      // The window at 60 s holds seconds 1 to 60: 658 messages (second 0 held 2), 10.97/s; 340 / 10.97 = 31 s.
      b.ratePerSecond(60 * s) shouldBe (658.0 / 60) +- 1e-9
      w.head shouldBe "at 11.0 messages/s the budget (340 left) runs out 31 s into the 600 s left of the half"
      b.describe(
        60 * s) shouldBe "team messages (team 12, UDP 10012): 340 of 1000 left, 660 counted, 11.0/s, GameController says 990"
      // The rate forgets what is older than the window.
      b.ratePerSecond(200 * s) shouldBe 0.0
    }
  }

  "The GameController sources" should {
    val a = new InetSocketAddress("10.0.0.5", 3838)
    val b2 = new InetSocketAddress("10.0.0.6", 3838)
    val sameHost = new InetSocketAddress("10.0.0.5", 41000)

    "take game state from the first trusted one only while it sends, and warn of the other, whose packet numbers interleave" in {
      var sources = GameControllerSources()
      val uses = (0 until 10).map { i =>
        val (from, number) = if (i % 2 == 0) (a, 10 + i / 2) else (sameHost, 200 + i / 2)
        val (next, use) = sources.packet(from, Some(number), trusted = true, i * s / 4)
        sources = next
        use
      }
      uses shouldBe Vector(true, false, true, false, true, false, true, false, true, false)
      sources.warnings(3 * s) shouldBe Vector("2 GameControllers on this field: game state from 10.0.0.5:3838 only; " +
        "10.0.0.5:41000 (trusted, ignored while the other sends)")
      // The first goes quiet: after 5 s the other one counts.
      sources.packet(sameHost, Some(250), trusted = true, 10 * s)._2 shouldBe true
    }
    "warn of an untrusted GameController without ever taking its state, and forget a quiet one" in {
      var sources = GameControllerSources()
      sources = sources.packet(a, Some(1), trusted = true, 0L)._1
      val (next, use) = sources.packet(b2, Some(7), trusted = false, s)
      use shouldBe false
      next.warnings(2 * s).head should include("10.0.0.6:3838 (untrusted, ignored)")
      next.warnings(7 * s) shouldBe empty
      // Alone, the untrusted one gives no state, and the warning says so rather than naming a chosen one.
      val alone = GameControllerSources().packet(b2, Some(7), trusted = false, s)._1
      alone.warnings(2 * s) shouldBe
        Vector(
          "no game state: the GameController heard, 10.0.0.6:3838, is untrusted (naogateway.game-controller.trusted-sources)")
      alone.packet(new InetSocketAddress("10.0.0.6", 41000), Some(8), trusted = false, 2 * s)._1.warnings(
        3 * s) shouldBe Vector(
        "no game state: the 2 GameControllers heard are untrusted: 10.0.0.6:3838, 10.0.0.6:41000 (naogateway.game-controller.trusted-sources)")
      // The chosen one gone quiet while a trusted one sends: it takes over with its next packet, nothing to warn of.
      val handover = GameControllerSources().packet(a, Some(1), trusted = true, 0L)._1
        .packet(sameHost, Some(5), trusted = true, 4 * s)._1
      handover.warnings(6 * s) shouldBe empty
      // Bounded: however many senders, at most MaxSenders are remembered.
      val many = (1 to 50).foldLeft(next)((acc, i) =>
        acc.packet(new InetSocketAddress("10.0.1.1", i), Some(i), trusted = false, i * s)._1)
      many.heard.size shouldBe GameControllerSources.MaxSenders
    }
  }
}
