package naogateway.api

import naogateway.wire.gamecontroller.{GameControlVersion, GameState}

/** What the competition gate decides on (docs/protocol.md §10.7): the game state the trusted GameController last gave,
  * the wait before the gate opens again, or the fact that its last packet could not be read. The GameController watch
  * gives the outbox one with every packet, and the outbox asks `CompetitionGate.closes`.
  */
sealed trait GameReading extends Product with Serializable

/** The readings the gate knows. */
object GameReading {

  /** A packet of a known version said `state` (`version` is `None` when a test or a tool gives the state alone). */
  final case class Known(state: GameState, version: Option[GameControlVersion] = None) extends GameReading

  /** A packet of a version the gateway does not know, read by the header versions 18 to 20 share (§10.8). */
  final case class HeaderOnly(state: GameState, version: Int, packetBytes: Int) extends GameReading

  /** A control packet from the trusted GameController that no codec reads (a version yet to come, a wrong size). */
  final case class Unreadable(reason: String) extends GameReading

  /** The trusted GameController says the game does not run (`state`), but the gate stays closed for `leftMillis` more
    * of such packets; `contradictions` counts the packets that restarted that wait so far.
    */
  final case class Opening(state: GameState, leftMillis: Long, contradictions: Long) extends GameReading

  /** Competition mode before the trusted GameController's first packet: closed. */
  case object NotHeard extends GameReading

  /** No game (the rule off, or a test's default): the gate open. */
  val Nothing: GameReading = Known(GameState.Initial)
}
