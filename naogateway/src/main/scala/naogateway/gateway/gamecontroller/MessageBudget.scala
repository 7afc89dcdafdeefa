package naogateway.gateway.gamecontroller

import naogateway.wire.gamecontroller.{GameControlData, GamePhase, GameState, HslGameData}

/** The team-message rules of the Humanoid Soccer League's GameController (`naogateway.game-controller.team-messages`;
  * its `params.yaml` and README "Message Counting").
  *
  * @param teamNumber
  *   our team number; its messages go to UDP 10000 + teamNumber. 0 = not counted
  * @param maxBytes
  *   a message larger than this resets the team's score
  * @param perGame
  *   messages a team may send in a game
  * @param perExtraMinute
  *   added for each minute of additional time
  * @param perExtraTime
  *   added when a drawn game goes into extra time (the HSL GameController's `StartExtraTime`: 6000, a figure its source
  *   still marks to do, so it is a setting here)
  * @param rateWindowSeconds
  *   the window over which the current rate is measured
  */
final case class TeamMessageSettings(
    teamNumber: Int = 0,
    maxBytes: Int = 512,
    perGame: Int = 12000,
    perExtraMinute: Int = 600,
    rateWindowSeconds: Int = 60,
    maxDatagramsPerSecond: Int = 2000,
    perExtraTime: Int = 6000
) {
  require(maxDatagramsPerSecond > 0, "team-messages.max-datagrams-per-second must be positive")
  require(teamNumber >= 0 && teamNumber <= 254,
    s"game-controller.team-messages.team-number $teamNumber is not a team number (0 = off)")
  require(maxBytes > 0 && perGame >= 0 && perGame <= 0xffff && perExtraMinute >= 0 && perExtraTime >= 0,
    "team-messages limits must be positive")
  require(rateWindowSeconds >= 5 && rateWindowSeconds <= 600, "team-messages.rate-window must be 5 s to 10 min")

  /** Whether the gateway counts team messages at all. */
  def enabled: Boolean = teamNumber > 0

  /** The UDP port the team's messages go to. */
  def port: Int = 10000 + teamNumber
}

/** The team's message budget, counted as the GameController counts it, from the messages the gateway hears on the team
  * port and the trusted GameController's packets: a message counts in READY, SET and PLAYING but not in a penalty
  * shoot-out; one over `maxBytes`, or one when the budget is 0, is illegal (the GameController resets the score to 0);
  * the budget goes down by one for every counted message while above 0. A minute of additional time (the half's clock
  * jumping up by a minute outside PLAYING, as the GameController's "+" does) adds `perExtraMinute`, unless the team
  * communicated illegally; so does the start of extra time (the game phase turning from normal, in the second half, to
  * extra time) with `perExtraTime`. A new game (a first half after a second half, in the normal phase) starts from
  * `perGame` again. Pure; the gateway holds one and feeds it.
  *
  * @param remaining
  *   the budget as counted here
  * @param counted
  *   messages counted (in READY, SET, PLAYING outside a shoot-out)
  * @param uncounted
  *   messages heard outside those states
  * @param oversize
  *   messages over `maxBytes`
  * @param overBudget
  *   messages counted with the budget at 0
  * @param phase
  *   the game phase the last packet that told it said (a version-19 or -20 one outside a timeout)
  * @param extraTimeGranted
  *   whether this game's extra time has started (and `perExtraTime` was added, unless the team was illegal)
  * @param reported
  *   the trusted GameController's own `messageBudget` for our team (versions 19 and 20)
  * @param rateBuckets
  *   counted messages per whole second of the gateway's clock, the last `rateWindowSeconds` of them
  */
private[naogateway] final case class MessageBudget(
    settings: TeamMessageSettings,
    remaining: Int,
    counted: Long = 0L,
    uncounted: Long = 0L,
    oversize: Long = 0L,
    overBudget: Long = 0L,
    state: Option[GameState] = None,
    shootOut: Boolean = false,
    firstHalf: Option[Boolean] = None,
    secsRemaining: Option[Long] = None,
    extraMinutes: Int = 0,
    phase: Option[GamePhase] = None,
    extraTimeGranted: Boolean = false,
    reported: Option[Int] = None,
    rateBuckets: Vector[(Long, Int)] = Vector.empty
) {
  import MessageBudget._

  /** Whether the team communicated illegally (over size or over budget): the GameController has reset its score. */
  def illegal: Boolean = oversize > 0 || overBudget > 0

  /** Whether a message arriving now counts. */
  def counting: Boolean =
    !shootOut && state.exists(s => s == GameState.Ready || s == GameState.Set || s == GameState.Playing)

  /** One team message of `bytes` bytes heard at `nowNanos`. */
  def message(bytes: Int, nowNanos: Long): MessageBudget =
    if (!counting) copy(uncounted = uncounted + 1)
    else {
      val second = nowNanos / SecondNanos
      val buckets = rateBuckets.lastOption match {
        case Some((s, n)) if s == second => rateBuckets.init :+ (s -> (n + 1))
        case _ => (rateBuckets :+ (second -> 1)).filter(_._1 > second - settings.rateWindowSeconds)
      }
      copy(
        remaining = math.max(0, remaining - 1),
        counted = counted + 1,
        oversize = oversize + (if (bytes > settings.maxBytes) 1 else 0),
        overBudget = overBudget + (if (remaining == 0) 1 else 0),
        rateBuckets = buckets
      )
    }

  /** A packet of the trusted GameController. */
  def game(data: GameControlData): MessageBudget = {
    // Only versions 19 and 20 tell the phase; a timeout hides it, so the phase before it holds.
    val told = data match {
      case d: HslGameData if d.gamePhase != GamePhase.Timeout => Some(d.gamePhase)
      case _                                                  => None
    }
    // StartExtraTime: from the normal phase's second half to extra time's first.
    val extraTimeStarts =
      phase.contains(GamePhase.Normal) && firstHalf.contains(false) && told.contains(GamePhase.ExtraTime)
    val newGame = firstHalf.contains(false) && data.firstHalf && !told.contains(GamePhase.ExtraTime)
    val base = if (newGame) MessageBudget(settings, settings.perGame) else this
    val granted = if (extraTimeStarts && !base.illegal) settings.perExtraTime else 0
    // The "+" of the GameController: a minute more on the half's clock, only outside PLAYING, within one half.
    val extra = !newGame && firstHalf.contains(data.firstHalf) && data.gameState != GameState.Playing &&
      secsRemaining.exists(before =>
        data.secsRemaining - before >= ExtraMinuteSeconds - 1 && data.secsRemaining - before <= ExtraMinuteSeconds + 1)
    val ours = data match {
      case d: HslGameData => Seq(d.team0, d.team1).find(_.teamNumber == settings.teamNumber).map(_.messageBudget)
      case _              => None
    }
    base.copy(
      remaining = (if (extra && !base.illegal) base.remaining + settings.perExtraMinute else base.remaining) + granted,
      extraMinutes = base.extraMinutes + (if (extra) 1 else 0),
      phase = told.orElse(base.phase),
      extraTimeGranted = base.extraTimeGranted || extraTimeStarts,
      state = Some(data.gameState),
      shootOut = data.penaltyShootOut,
      firstHalf = Some(data.firstHalf),
      secsRemaining = Some(data.secsRemaining),
      reported = ours.orElse(if (newGame) None else reported)
    )
  }

  /** Counted messages per second over the rate window ending at `nowNanos`. */
  def ratePerSecond(nowNanos: Long): Double = {
    val second = nowNanos / SecondNanos
    rateBuckets.filter(_._1 > second - settings.rateWindowSeconds).map(_._2).sum.toDouble / settings.rateWindowSeconds
  }

  /** What needs the team's attention at `nowNanos`: messages over the size limit, messages over the budget, and a
    * budget that would run out before the end of the half at the current rate.
    */
  def warnings(nowNanos: Long): Vector[String] = {
    val rate = ratePerSecond(nowNanos)
    val left = secsRemaining.filter(_ > 0)
    Vector(
      Option.when(oversize > 0)(
        s"$oversize team message(s) over ${settings.maxBytes} bytes: the GameController resets the score to 0"),
      Option.when(overBudget > 0)(
        s"$overBudget team message(s) over the budget: the GameController resets the score to 0"),
      left.filter(secs => counting && rate * secs > remaining).map(secs =>
        f"at $rate%.1f messages/s the budget ($remaining left) runs out ${(remaining / rate).toLong} s into the " +
          f"$secs s left of the half")
    ).flatten
  }

  /** One line for the status view and `robotctl status`. */
  def describe(nowNanos: Long): String =
    f"team messages (team ${settings.teamNumber}, UDP ${settings.port}): $remaining of " +
      f"${settings.perGame + extraMinutes * settings.perExtraMinute +
          (if (extraTimeGranted) settings.perExtraTime else 0)} left, " +
      f"$counted counted, ${ratePerSecond(nowNanos)}%.1f/s" +
      reported.fold("")(r => s", GameController says $r") + (if (counting) "" else " (not counting now)")
}

/** Constructors and constants of message budgets. */
private[naogateway] object MessageBudget {

  private val SecondNanos = 1000000000L

  /** Seconds the GameController's "+" adds to the half's clock. */
  val ExtraMinuteSeconds: Long = 60L

  /** A fresh budget for a game. */
  def apply(settings: TeamMessageSettings): MessageBudget = MessageBudget(settings, settings.perGame)
}
