package naogateway.wire

/** A robot's posture as docs/protocol.md §7.2 names it: what `motion.getPosture`, the `motion.posture` reply,
  * `RobotHealth.posture` and the simulated robot's `Status.currentState` say.
  */
sealed abstract class Posture(val name: String) extends Product with Serializable

/** The postures of docs/protocol.md §7.2, and the way to carry one this build does not know. */
object Posture {

  /** A posture a `motion.posture` call may ask for. */
  sealed abstract class Target(name: String) extends Posture(name)

  /** Sitting. */
  case object Sit extends Target("sit")

  /** Standing. */
  case object Stand extends Target("stand")

  /** Crouching. */
  case object Crouch extends Target("crouch")

  /** Walking under a `motion.walk` lease. */
  case object Walking extends Posture("walking")

  /** A posture motion is running. */
  case object Moving extends Posture("moving")

  /** The robot fell (the simulated robot never does). */
  case object Fallen extends Posture("fallen")

  /** A posture a robot reported that this build does not know. A newer firmware may report one; the status that carries
    * it must still reach its subscribers, so it is kept as reported rather than refused. Built only by [[reported]], so
    * a known name never ends up here.
    */
  final case class Unknown private (override val name: String) extends Posture(name)

  /** Every posture docs/protocol.md §7.2 names, in its order. */
  val known: Vector[Posture] = Vector(Sit, Stand, Crouch, Walking, Moving, Fallen)

  /** The postures a `motion.posture` call may ask for, in the protocol's order. */
  val targets: Vector[Target] = Vector(Sit, Stand, Crouch)

  private val byName: Map[String, Posture] = known.map(p => p.name -> p).toMap

  /** The posture a robot reported: a known one, or [[Unknown]] carrying the name as it came (never fails). */
  def reported(name: String): Posture = byName.getOrElse(name, Unknown(name))

  /** The posture a caller asks for, or a sentence naming the ones it may ask for. */
  def target(name: String): Either[String, Target] =
    targets.find(_.name == name).toRight(s"unknown posture '$name' (${targets.map(_.name).mkString(", ")})")
}
