package naogateway.api

/** The sending classes of the traffic budget; a lower rank goes first, and Safety is never held back. */
sealed abstract class Priority(val rank: Int, val name: String) extends Product with Serializable

/** The four classes, most urgent first. */
object Priority {

  /** Stop and safe-posture commands: sent at once, counted but never delayed by the budget. */
  case object Safety extends Priority(0, "safety")

  /** Liveness probes. */
  case object Heartbeat extends Priority(1, "heartbeat")

  /** Ordinary calls and commands. */
  case object Command extends Priority(2, "command")

  /** Debug option requests and camera traffic: the first to wait when the budget is full. */
  case object Debug extends Priority(3, "debug")

  val all: Vector[Priority] = Vector(Safety, Heartbeat, Command, Debug)
}
