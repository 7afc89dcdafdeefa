package naogateway.wire

/** A group of actuators one app may hold at a time (a lease is per robot and group). */
sealed abstract class ActuatorGroup(val name: String) extends Product with Serializable

/** The actuator groups: walking and posture, head, arms, speech. */
object ActuatorGroup {

  /** Walking, stopping and postures (and `system.reset`, which moves the robot). */
  case object Walk extends ActuatorGroup("walk")

  /** The head's pan and tilt. */
  case object Head extends ActuatorGroup("head")

  /** The four arm joints. */
  case object Arms extends ActuatorGroup("arms")

  /** The speaker. */
  case object Speech extends ActuatorGroup("speech")

  /** The groups that are a robot's command slots: a newer target in one replaces an older one (RpcMethod.slot). */
  val slots: Vector[ActuatorGroup] = Vector(Walk, Head, Arms)

  /** Every group, in the order the docs list them. */
  val all: Vector[ActuatorGroup] = Vector(Walk, Head, Arms, Speech)

  /** The group named `name`, or a sentence naming the groups there are. */
  def parse(name: String): Either[String, ActuatorGroup] =
    all.find(_.name == name).toRight(s"unknown actuator group '$name' (${all.map(_.name).mkString(", ")})")
}
