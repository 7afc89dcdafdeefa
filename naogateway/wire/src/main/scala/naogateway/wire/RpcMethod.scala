package naogateway.wire

/** One method of the RPC contract the robot serves (docs/protocol.md 7.2).
  *
  * @param idempotent
  *   whether it may run twice, so it may be called again when no answer came (protocol.md 7.1)
  * @param slot
  *   the actuator slot whose order it takes part in, if any
  * @param read
  *   whether it only reads the robot's state: it moves and says nothing, so it needs no lease (docs/zeromq.md 5). No
  *   default: a default argument lives in the companion object, and reading it would start that object's initialisation
  *   from a case object's (see the constants below).
  */
sealed abstract class RpcMethod(val module: String, val method: String, val idempotent: Boolean,
    val slot: Option[ActuatorGroup], val read: Boolean)
    extends Product with Serializable {

  /** `module.method`, as in logs, errors and the docs. */
  def name: String = s"$module.$method"

  /** Whether a newer call of its slot replaces it: a target (walk velocities, head or arm angles), not a stop or
    * posture.
    */
  def latestWins: Boolean = slot.isDefined && this != RpcMethod.Stop && this != RpcMethod.Posture

  /** A call of this method with `params`. */
  def call(params: RpcValue*): RpcCall = RpcCall(module, method, params.toVector)
}

/** The method table: the one place that names the robot's methods. */
object RpcMethod {

  // Constants (final, no type ascription), so the case objects below read them inlined: a case object initialised
  // first must not start this object's initialisation, whose `all` needs that case object already done.

  /** The module of the motions (walk, stop, head, arms, posture, getPosture). */
  final val MotionModule = "motion"

  /** The module of speech (say). */
  final val SpeechModule = "speech"

  /** The module of the robot itself (battery, ping, reset). */
  final val SystemModule = "system"

  /** Walk with these velocities; the robot's 500 ms lease needs it refreshed. */
  case object Walk extends RpcMethod(MotionModule, "walk", idempotent = true, Some(ActuatorGroup.Walk), read = false)

  /** End walking. */
  case object Stop extends RpcMethod(MotionModule, "stop", idempotent = true, Some(ActuatorGroup.Walk), read = false)

  /** Turn the head. */
  case object Head extends RpcMethod(MotionModule, "head", idempotent = true, Some(ActuatorGroup.Head), read = false)

  /** Set the four arm joints. */
  case object Arms extends RpcMethod(MotionModule, "arms", idempotent = true, Some(ActuatorGroup.Arms), read = false)

  /** Move to a posture; answers when the motion has ended, and a second one during a motion is refused (busy). */
  case object Posture
      extends RpcMethod(MotionModule, "posture", idempotent = false, Some(ActuatorGroup.Walk), read = false)

  /** Read the posture. */
  case object GetPosture extends RpcMethod(MotionModule, "getPosture", idempotent = true, None, read = true)

  /** Speak a text: not repeated, the robot would say it twice. */
  case object Say extends RpcMethod(SpeechModule, "say", idempotent = false, None, read = false)

  /** Read the battery voltage. */
  case object Battery extends RpcMethod(SystemModule, "battery", idempotent = true, None, read = true)

  /** Read the uptime. */
  case object Ping extends RpcMethod(SystemModule, "ping", idempotent = true, None, read = true)

  /** Restart the robot: never repeated. */
  case object Reset extends RpcMethod(SystemModule, "reset", idempotent = false, None, read = false)

  /** Every method, in the order of the docs' table. */
  val all: Vector[RpcMethod] = Vector(Walk, Stop, Head, Arms, Posture, GetPosture, Say, Battery, Ping, Reset)

  private val byName: Map[(String, String), RpcMethod] = all.map(m => (m.module, m.method) -> m).toMap

  /** The method `module.method`, if the robot serves it. */
  def find(module: String, method: String): Option[RpcMethod] = byName.get((module, method))

  /** The method `call` calls, if the robot serves it. */
  def of(call: RpcCall): Option[RpcMethod] = find(call.module, call.method)

  /** The slot `call` takes part in, if any. */
  def slotOf(call: RpcCall): Option[ActuatorGroup] = of(call).flatMap(_.slot)

  /** Whether `call` only reads the robot's state (a method the table knows as a read): it needs no lease. */
  def isRead(call: RpcCall): Boolean = of(call).exists(_.read)

  /** Whether `call` may be called again when no answer came; a method the table does not know is not. */
  def idempotent(call: RpcCall): Boolean = of(call).exists(_.idempotent)
}
