package robotmiddleware

import naogateway.wire.{Posture => WirePosture, RpcMethod, RpcValue}

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

  /** Every group, in the order the docs list them. */
  val all: Vector[ActuatorGroup] = Vector(Walk, Head, Arms, Speech)

  /** The group named `name`, or a sentence naming the groups there are. */
  def parse(name: String): Either[String, ActuatorGroup] =
    all.find(_.name == name).toRight(s"unknown actuator group '$name' (${all.map(_.name).mkString(", ")})")
}

/** Something an app asks a robot to do. */
sealed trait Operation extends Product with Serializable {

  /** The group whose lease the operation needs, if any (reads need none). */
  def group: Option[ActuatorGroup]

  /** `module.method` on the robot. */
  def name: String
}

/** The operations of `RobotInterface`. */
object Operation {

  /** Walk with these velocities until changed or stopped (the middleware keeps the robot's walk lease fresh). */
  final case class Walk(vx: Double, vy: Double, omega: Double) extends Operation {
    require(Seq(vx, vy, omega).forall(v => !v.isNaN && !v.isInfinite), "walk velocities must be finite numbers")
    def group: Option[ActuatorGroup] = Some(ActuatorGroup.Walk)
    def name: String = RpcMethod.Walk.name
  }

  /** Stop walking. */
  final case class Stop() extends Operation {
    def group: Option[ActuatorGroup] = Some(ActuatorGroup.Walk)
    def name: String = RpcMethod.Stop.name
  }

  /** Turn the head (radians; pan ±2.0, tilt -0.6..0.5). */
  final case class Head(pan: Double, tilt: Double) extends Operation {
    def group: Option[ActuatorGroup] = Some(ActuatorGroup.Head)
    def name: String = RpcMethod.Head.name
  }

  /** Set the four arm joints (radians). */
  final case class Arms(leftShoulder: Double, leftElbow: Double, rightShoulder: Double, rightElbow: Double) extends Operation {
    def group: Option[ActuatorGroup] = Some(ActuatorGroup.Arms)
    def name: String = RpcMethod.Arms.name
  }

  /** Go to a posture (sit, stand or crouch); answers when the motion has ended. */
  final case class Posture(target: WirePosture.Target) extends Operation {
    def group: Option[ActuatorGroup] = Some(ActuatorGroup.Walk)
    def name: String = RpcMethod.Posture.name
  }

  /** Say a text. */
  final case class Say(text: String) extends Operation {
    def group: Option[ActuatorGroup] = Some(ActuatorGroup.Speech)
    def name: String = RpcMethod.Say.name
  }

  /** Any call of the robot's RPC interface; motion and speech calls need the matching lease. */
  final case class RawCall(module: String, method: String, params: Vector[RpcValue]) extends Operation {
    def group: Option[ActuatorGroup] = (module, method) match {
      case _ if RpcMethod.find(module, method).contains(RpcMethod.Head) => Some(ActuatorGroup.Head)
      case _ if RpcMethod.find(module, method).contains(RpcMethod.Arms) => Some(ActuatorGroup.Arms)
      case ("motion", _)      => Some(ActuatorGroup.Walk)
      case ("speech", _)      => Some(ActuatorGroup.Speech)
      case ("system", "reset") => Some(ActuatorGroup.Walk)
      case _                  => None
    }
    def name: String = s"$module.$method"
  }
}

/** Why an operation or a lease request failed; every failure of `RobotInterface` is one of these. */
sealed abstract class RobotFailure(message: String) extends Exception(message) with Product with Serializable

/** The typed failures of `RobotInterface`. */
object RobotFailure {

  /** The robot is offline; nothing was sent. */
  final case class RobotOffline(robotId: Int) extends RobotFailure(s"robot $robotId is offline")

  /** No such robot. */
  final case class UnknownRobot(robotId: Int) extends RobotFailure(s"no robot $robotId is known")

  /** The app does not hold the lease the operation needs. */
  final case class LeaseNotHeld(robotId: Int, group: ActuatorGroup, holder: Option[String])
      extends RobotFailure(s"lease '${group.name}' of robot $robotId is not held by this app" + holder.fold("")(h => s" (held by $h)"))

  /** A competition rule forbids sending now. */
  final case class RuleGate(rule: String) extends RobotFailure(rule)

  /** No answer in time. */
  final case class Timeout(robotId: Int, operation: String, millis: Long)
      extends RobotFailure(s"robot $robotId did not answer $operation within $millis ms")

  /** The robot answered with an error. */
  final case class RobotError(robotId: Int, error: String) extends RobotFailure(s"robot $robotId: $error")

  /** The middleware holds the robot in a safe state (low battery, lost link) and refuses motion. */
  final case class SafetyHold(robotId: Int, reason: String) extends RobotFailure(s"robot $robotId is held safe: $reason")

  /** Too much is waiting for this robot. */
  final case class Overloaded(robotId: Int, detail: String) extends RobotFailure(s"robot $robotId is overloaded: $detail")
}

/** The messages of an app's session actor: the middleware's events plus local subscriptions. */
sealed trait SessionMessage

/** Local requests to an app's session actor. */
object SessionMessage {

  /** Forwards every `AppEvent` to `subscriber` until it stops. */
  final case class SubscribeAppEvents(subscriber: akka.actor.typed.ActorRef[AppEvent]) extends SessionMessage

  /** Ends the session: the middleware releases the app's leases and stops its robots. */
  case object Close extends SessionMessage
}

/** What the middleware tells an app about its leases and robots. */
sealed trait AppEvent extends SessionMessage with Product with Serializable

/** The events an app can receive. */
object AppEvent {

  /** A higher-priority app took a lease away. */
  final case class LeasePreempted(robotId: Int, group: ActuatorGroup, byApp: String) extends AppEvent

  /** The middleware stopped the robot for safety; the app's motion is refused until `SafetyCleared`. */
  final case class SafetyStop(robotId: Int, reason: String) extends AppEvent

  /** The safety condition cleared. */
  final case class SafetyCleared(robotId: Int) extends AppEvent
}
