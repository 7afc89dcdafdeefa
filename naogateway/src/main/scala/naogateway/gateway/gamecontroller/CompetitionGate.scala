package naogateway.gateway.gamecontroller

import naogateway.wire.gamecontroller.{GameControlVersion, GameState}
import naogateway.api.GameReading

/** The competition rule (docs/protocol.md §10.7) as pure functions, shared by the outbox and the GameController watch:
  * the base station must not send to robots while the game runs, which every version says with the same three states.
  */
private[naogateway] object CompetitionGate {

  /** The rule that closes the gate, in words for errors and logs. */
  val NoSendingWhileGameRuns: String =
    "competition rule: the base station must not send to robots while the game is running (READY, SET or PLAYING)"

  /** Whether a game state counts as "the game is running": READY, SET and PLAYING, in every version alike. */
  def gameRunning(state: GameState): Boolean =
    state == GameState.Ready || state == GameState.Set || state == GameState.Playing

  /** Whether the gate is closed on `reading` (in competition mode). */
  def closes(reading: GameReading): Boolean = reading match {
    case GameReading.Known(state, _)         => gameRunning(state)
    case GameReading.HeaderOnly(state, _, _) => gameRunning(state)
    case _: GameReading.Unreadable           => true
    case _: GameReading.Opening              => true
    case GameReading.NotHeard                => true
  }

  /** Why the gate is closed on `reading`, for the status screen and robotctl; `None` when it is open. What changes from
    * packet to packet (seconds, counts) stands in parentheses, so a view can tell a new reason from a new figure.
    */
  def why(reading: GameReading): Option[String] = reading match {
    case GameReading.Known(state, _) if gameRunning(state) => Some(s"the game is running ($state)")
    case GameReading.HeaderOnly(state, version, _) if gameRunning(state) =>
      Some(s"the game is running ($state, read from the shared header of unknown version $version)")
    case _: GameReading.Known | _: GameReading.HeaderOnly => None
    case GameReading.Unreadable(reason) => Some(s"the trusted GameController's packet cannot be read ($reason)")
    case GameReading.Opening(state, leftMillis, contradictions) =>
      Some(s"opening once the game has not run for a while ($state, ${(leftMillis + 999) / 1000} s more, " +
        s"$contradictions contradiction(s) so far)")
    case GameReading.NotHeard => Some("no packet from the trusted GameController yet (competition mode starts closed)")
  }

  /** Packet numbers that may be missing between two that still follow one another (lost on the WiFi). */
  val MaxLostPackets: Int = 3

  /** Whether packet number `next` follows `last`: one to [[MaxLostPackets]] + 1 ahead, wrapping at 256. */
  def follows(last: Int, next: Int): Boolean = {
    val ahead = (next - last + 256) % 256
    ahead >= 1 && ahead <= MaxLostPackets + 1
  }
}

/** The gate over the trusted GameController's packets (docs/protocol.md §10.7): it closes fast and opens slowly. Any
  * trusted packet saying the game runs, and any trusted packet that cannot be read, closes it at once; it opens only
  * once every trusted packet for `openAfterNanos` said the game does not run, with packet numbers that follow one
  * another. A packet saying the game runs, or a packet number out of sequence, while it waits to open is a
  * contradiction: counted, and the wait starts again. Pure; the GameController watch holds one.
  *
  * @param reading
  *   what the gate gives the outbox now
  * @param quietSince
  *   when the present run of packets saying the game does not run began, while the gate waits to open
  * @param lastPacketNumber
  *   the number of the last packet that counted
  * @param contradictions
  *   packets that contradicted a wait to open, since the start
  */
private[naogateway] final case class GateLatch(
    openAfterNanos: Long,
    reading: GameReading,
    quietSince: Option[Long] = None,
    lastPacketNumber: Option[Int] = None,
    contradictions: Long = 0L
) {

  /** Whether the gate lets datagrams through (in competition mode). */
  def open: Boolean = !CompetitionGate.closes(reading)

  /** A readable packet from the trusted GameController saying `said` (a [[GameReading.Known]] or
    * [[GameReading.HeaderOnly]]), numbered `packetNumber` (version 7 has none), at `nowNanos`.
    */
  def packet(said: GameReading, packetNumber: Option[Int], nowNanos: Long): GateLatch =
    if (CompetitionGate.closes(said))
      copy(reading = said, quietSince = None, lastPacketNumber = packetNumber,
        contradictions = contradictions + (if (quietSince.isDefined) 1 else 0))
    else if (open || openAfterNanos == 0L) copy(reading = said, quietSince = None, lastPacketNumber = packetNumber)
    else {
      val inSequence = (lastPacketNumber, packetNumber) match {
        case (Some(last), Some(next)) => CompetitionGate.follows(last, next)
        case _                        => true
      }
      val state = said match {
        case GameReading.Known(s, _)         => s
        case GameReading.HeaderOnly(s, _, _) => s
        case _                               => GameState.Initial
      }
      quietSince match {
        case Some(since) if inSequence && nowNanos - since >= openAfterNanos =>
          copy(reading = said, quietSince = None, lastPacketNumber = packetNumber)
        case Some(since) if inSequence =>
          copy(reading = GameReading.Opening(state, (since + openAfterNanos - nowNanos) / 1000000L, contradictions),
            lastPacketNumber = packetNumber)
        case Some(_) =>
          copy(
            reading = GameReading.Opening(state, openAfterNanos / 1000000L, contradictions + 1),
            quietSince = Some(nowNanos),
            lastPacketNumber = packetNumber,
            contradictions = contradictions + 1
          )
        case None =>
          copy(reading = GameReading.Opening(state, openAfterNanos / 1000000L, contradictions),
            quietSince = Some(nowNanos), lastPacketNumber = packetNumber)
      }
    }

  /** A packet from the trusted GameController that could not be read: closed at once, the wait to open starts again. */
  def unreadable(reason: String): GateLatch =
    copy(reading = GameReading.Unreadable(reason), quietSince = None, lastPacketNumber = None,
      contradictions = contradictions + (if (quietSince.isDefined) 1 else 0))
}

/** Constructors of gate latches. */
private[naogateway] object GateLatch {

  /** The gate at the gateway's start: closed in competition mode until the trusted GameController said for
    * `openAfterNanos` that the game does not run; open otherwise (the rule is off, the reading only shown).
    */
  def start(competition: Boolean, openAfterNanos: Long): GateLatch =
    GateLatch(openAfterNanos, if (competition) GameReading.NotHeard else GameReading.Nothing)

  /** The reading of a readable packet of a known version. */
  def known(state: GameState, version: GameControlVersion): GameReading = GameReading.Known(state, Some(version))
}
