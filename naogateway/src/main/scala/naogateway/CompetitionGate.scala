package naogateway

import naogateway.wire.gamecontroller.{GameControlVersion, GameState}

/** The competition rule (docs/protocol.md §10.6) as one pure function, shared by the outbox and the ZeroMQ link: the
  * base station must not send to robots while the game runs, which every version says with the same three states.
  */
private[naogateway] object CompetitionGate {

  /** The rule that closes the gate, in words for errors and logs. */
  val NoSendingWhileGameRuns: String =
    "competition rule: the base station must not send to robots while the game is running (READY, SET or PLAYING)"

  /** How long an unreadable packet from the trusted GameController keeps the gate closed, whatever readable ones say.
    */
  val UnreadableHoldNanos: Long = 3000000000L

  /** Whether a game state counts as "the game is running": READY, SET and PLAYING, in versions 7, 8, 12 and 19 alike.
    */
  def gameRunning(state: GameState): Boolean =
    state == GameState.Ready || state == GameState.Set || state == GameState.Playing

  /** Whether the gate closes on `reading` (in competition mode): while the game runs, and when the trusted
    * GameController's packet cannot be read, since that GameController may well be running a game.
    */
  def closes(reading: GameReading): Boolean = reading match {
    case GameReading.Known(state, _) => gameRunning(state)
    case GameReading.Unreadable(_)   => true
  }

  /** Why the gate is closed on `reading`, for the status screen and robotctl; `None` when it is open. */
  def why(reading: GameReading): Option[String] = reading match {
    case GameReading.Known(state, _) if gameRunning(state) => Some(s"the game is running ($state)")
    case GameReading.Known(_, _)                           => None
    case GameReading.Unreadable(reason) => Some(s"the trusted GameController's packet cannot be read: $reason")
  }

  /** The reading a packet from the trusted GameController gives at `nowNanos`: an unreadable one within
    * [[UnreadableHoldNanos]] (`lastUnreadable`, with its reason) outweighs a readable one, so a GameController that
    * broadcasts a version this gateway cannot read beside one it can does not open the gate every other packet.
    */
  def reading(state: GameState, version: GameControlVersion, lastUnreadable: Option[(Long, String)], nowNanos: Long)
      : GameReading =
    lastUnreadable match {
      case Some((at, reason)) if nowNanos - at < UnreadableHoldNanos => GameReading.Unreadable(reason)
      case _                                                         => GameReading.Known(state, Some(version))
    }
}
