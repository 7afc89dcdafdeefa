package naogateway.gateway.robot

/** What one keep-alive says about the robot's session: its `bootId` and uptime (either may be missing) and when the
  * gateway received it, in milliseconds of the gateway's monotonic clock.
  */
private[naogateway] final case class SessionMark(
    bootId: Option[Int], uptimeMillis: Option[Long], receivedAtMillis: Long) {

  /** Whether the keep-alive carries anything about the session at all. */
  def saysSomething: Boolean = bootId.isDefined || uptimeMillis.isDefined

  /** When the robot powered up, by the gateway's clock, if the keep-alive carries an uptime. */
  def bootAtMillis: Option[Long] = uptimeMillis.map(receivedAtMillis - _)
}

/** One session of a robot as the gateway believes it: its `bootId` (if it sends one), when it powered up by the
  * gateway's clock (`bootAtMillis`, if it sends an uptime) and the highest uptime seen in it.
  */
private[naogateway] final case class Session(
    bootId: Option[Int], bootAtMillis: Option[Long], lastUptimeMillis: Option[Long])

/** Restart recognition (docs/protocol.md 6.2, docs/architecture.md 10), pure: the session the gateway believes in and a
  * candidate new session with the number of keep-alives in a row that belong to it.
  *
  * A keep-alive '''belongs to''' a session when it does not carry another `bootId` and, if both have a clock, the
  * power-up time it implies (time received - uptime) is within [[SessionRule.ClockToleranceMillis]] of the session's. A
  * keep-alive that does not belong to the current session '''points to a new session''' when it carries another
  * `bootId`, or an uptime more than the tolerance below the highest one of the current session. Such a keep-alive
  * starts a candidate; the next keep-alives must belong to the candidate, one after another, and the `keepAlives`-th of
  * them makes the candidate the current session: the robot restarted. A keep-alive of the current session ends the
  * candidate, and so does one that belongs to neither (an odd keep-alive, ignored otherwise). So one odd keep-alive, or
  * forged ones between the robot's own, never make a restart.
  */
private[naogateway] final case class SessionRule(
    current: Option[Session], candidate: Option[Session], candidateKeepAlives: Int) {
  import SessionRule._

  /** The rule after one keep-alive, and whether that keep-alive completed a new session (the robot restarted). */
  def step(mark: SessionMark, keepAlives: Int): (SessionRule, Boolean) =
    if (!mark.saysSomething) (this, false)
    else
      current match {
        case None                                    => (SessionRule(Some(start(mark)), None, 0), false)
        case Some(session) if belongs(session, mark) => (SessionRule(Some(follow(session, mark)), None, 0), false)
        case Some(session) =>
          candidate match {
            case Some(c) if belongs(c, mark)            => grow(follow(c, mark), candidateKeepAlives + 1, keepAlives)
            case _ if pointsToNewSession(session, mark) => grow(start(mark), 1, keepAlives)
            case _                                      => (SessionRule(current, None, 0), false)
          }
      }

  private def grow(c: Session, count: Int, keepAlives: Int): (SessionRule, Boolean) =
    if (count >= keepAlives) (SessionRule(Some(c), None, 0), true) else (SessionRule(current, Some(c), count), false)
}

/** The restart rule's constants and its start. */
private[naogateway] object SessionRule {

  /** Nothing heard yet. */
  val empty: SessionRule = SessionRule(None, None, 0)

  /** How far the power-up time one keep-alive implies may lie from its session's (network delay, a late mailbox), and
    * how far an uptime must fall below the session's to point to a new session (so reordered keep-alives do not).
    */
  val ClockToleranceMillis: Long = 1000L

  /** How far a session's power-up time follows each keep-alive of it: enough for clock drift and slowly changing
    * delays, little enough that a forged keep-alive that still belongs to the session moves it by at most this much.
    */
  val ClockFollowMillis: Long = 5L

  /** `RobotHealth.uptimeMs` is a `uint32`: it wraps after about 49.7 days, which is no restart. */
  val UptimeWrapMillis: Long = 1L << 32

  private def start(mark: SessionMark): Session = Session(mark.bootId, mark.bootAtMillis, mark.uptimeMillis)

  private def sameBoot(a: Option[Int], b: Option[Int]): Boolean = (a, b) match {
    case (Some(x), Some(y)) => x == y
    case _                  => true
  }

  private def near(a: Long, b: Long): Boolean = {
    val d = math.abs(a - b)
    d <= ClockToleranceMillis || math.abs(d - UptimeWrapMillis) <= ClockToleranceMillis
  }

  /** Whether `mark` belongs to `session`: no other bootId, and (when both have a clock) the same power-up time. */
  def belongs(session: Session, mark: SessionMark): Boolean =
    sameBoot(session.bootId, mark.bootId) &&
      (for (a <- session.bootAtMillis; b <- mark.bootAtMillis) yield near(a, b)).getOrElse(true)

  /** Whether `mark`, not belonging to `session`, points to a new session: another bootId, or an uptime that went back.
    */
  def pointsToNewSession(session: Session, mark: SessionMark): Boolean =
    !sameBoot(session.bootId, mark.bootId) ||
      (for (before <- session.lastUptimeMillis; now <- mark.uptimeMillis)
        yield now + ClockToleranceMillis < before).getOrElse(false)

  /** `session` after a keep-alive that belongs to it. */
  private def follow(session: Session, mark: SessionMark): Session = {
    val bootAt = (session.bootAtMillis, mark.bootAtMillis) match {
      case (Some(a), Some(b)) if math.abs(b - a) <= ClockToleranceMillis =>
        Some(a + math.max(-ClockFollowMillis, math.min(ClockFollowMillis, b - a)))
      case (a, b) => a.orElse(b)
    }
    val uptime = (session.lastUptimeMillis, mark.uptimeMillis) match {
      // Across a wrap the uptime starts again low, and the session goes on.
      case (Some(a), Some(b)) => Some(if (b + ClockToleranceMillis < a) b else math.max(a, b))
      case (a, b)             => b.orElse(a)
    }
    Session(mark.bootId.orElse(session.bootId), bootAt, uptime)
  }
}
