package naogateway.api.recording

import naogateway.api.{GatewayEvent, Priority}

/** A gateway decision worth recording, handed over as data and written as JSON by the writer thread. */
sealed trait Decision extends Product with Serializable

/** The decisions. */
object Decision {

  /** A robot or game event the gateway published (online, offline, restarted, link quality, game state). */
  final case class Published(event: GatewayEvent) extends Decision

  /** What the outbox did with one datagram for robot `robotId`: `sent`, `queued`, `refused-by-rule`, `dropped`. */
  final case class Outgoing(robotId: Int, priority: Priority, outcome: String, bytes: Array[Byte]) extends Decision

  /** The competition gate opened or closed on `reading` (a game state, or a packet that could not be read). */
  final case class Gate(open: Boolean, reading: naogateway.api.GameReading) extends Decision

  /** The team budget's state: bytes each way over the last second, the limit, the queues. */
  final case class Budget(outBytes: Long, inBytes: Long, limit: Int, queued: Map[String, Int]) extends Decision
}
