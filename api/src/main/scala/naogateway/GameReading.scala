package naogateway

import naogateway.wire.gamecontroller.{GameControlVersion, GameState}

/** What the competition gate decides on: the game state the trusted GameController last gave, or the fact that its last
  * packet could not be read. The outbox and every ZeroMQ robot's link hold one and ask [[CompetitionGate.closes]].
  */
sealed trait GameReading extends Product with Serializable

/** The readings the gate knows. */
object GameReading {

  /** A packet of a known version said `state` (`version` is `None` when a test or a tool gives the state alone). */
  final case class Known(state: GameState, version: Option[GameControlVersion] = None) extends GameReading

  /** A control packet from the trusted GameController that no codec reads (a version yet to come, a wrong size). */
  final case class Unreadable(reason: String) extends GameReading

  /** Nothing heard yet: the gate stays open (no game, or no GameController on this field). */
  val Nothing: GameReading = Known(GameState.Initial)
}
