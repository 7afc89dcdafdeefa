package robotmiddleware

import naogateway.wire.ActuatorGroup

import naogateway.wire.{Posture => WirePosture, RpcMethod, RpcValue}

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
  final case class Arms(
      leftShoulder: Double, leftElbow: Double, rightShoulder: Double, rightElbow: Double) extends Operation {
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

  /** Any call of the robot's RPC interface; motion and speech calls need the matching lease, reads (the method table's
    * `read`: `motion.getPosture`, `system.battery`, `system.ping`) none.
    */
  final case class RawCall(module: String, method: String, params: Vector[RpcValue]) extends Operation {
    def group: Option[ActuatorGroup] = RpcMethod.find(module, method) match {
      case Some(m) if m.read     => None
      case Some(RpcMethod.Head)  => Some(ActuatorGroup.Head)
      case Some(RpcMethod.Arms)  => Some(ActuatorGroup.Arms)
      case Some(RpcMethod.Reset) => Some(ActuatorGroup.Walk)
      // The rest of these modules, known or not, takes the walk or speech lease: an unknown one may move or speak.
      case _ if module == RpcMethod.MotionModule => Some(ActuatorGroup.Walk)
      case _ if module == RpcMethod.SpeechModule => Some(ActuatorGroup.Speech)
      case _                                     => None
    }
    def name: String = s"$module.$method"
  }
}

/** Who holds a robot's leases (group to app name) and, while the middleware holds the robot safe, why and how the hold
  * ends: what `robotctl status` and `robotctl doctor` show (`RobotInterface.holds`).
  */
final case class RobotHolds(robotId: Int, leases: Map[ActuatorGroup, String], safetyHold: Option[String]) {

  /** The lease holders as people read them, in the docs' group order: `walk=teleop head=zeromq`, or `-`. */
  def describeLeases: String = {
    val held = ActuatorGroup.all.flatMap(g => leases.get(g).map(app => s"${g.name}=$app"))
    if (held.isEmpty) "-" else held.mkString(" ")
  }
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
