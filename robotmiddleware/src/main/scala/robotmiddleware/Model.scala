package robotmiddleware

import naogateway.wire.ActuatorGroup

import naogateway.wire.{Posture => WirePosture, RpcCall, RpcMethod, RpcValue}

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

  /** The robot call `operation` becomes, the method's name and parameters from the `RpcMethod` table. */
  def toCall(operation: Operation): RpcCall = operation match {
    case Walk(vx, vy, omega)             => RpcMethod.Walk.call(number(vx), number(vy), number(omega))
    case Stop()                          => RpcMethod.Stop.call()
    case Head(pan, tilt)                 => RpcMethod.Head.call(number(pan), number(tilt))
    case Arms(ls, le, rs, re)            => RpcMethod.Arms.call(number(ls), number(le), number(rs), number(re))
    case Posture(target)                 => RpcMethod.Posture.call(RpcValue.Text(target.name))
    case Say(text)                       => RpcMethod.Say.call(RpcValue.Text(text))
    case RawCall(module, method, params) => RpcCall(module, method, params)
  }

  /** The operation a robot call asks for, keyed by the `RpcMethod` table (`toCall`'s inverse): a known method's typed
    * operation, any other call a `RawCall`; or why its parameters cannot be right.
    */
  def fromCall(call: RpcCall): Either[String, Operation] = {
    def checked(operation: => Operation): Either[String, Operation] =
      try Right(operation)
      catch {
        case e: IllegalArgumentException => Left(String.valueOf(e.getMessage).stripPrefix("requirement failed: "))
      }
    RpcMethod.of(call) match {
      case Some(RpcMethod.Walk) => numbers(call, "vx", "vy", "omega").flatMap(v => checked(Walk(v(0), v(1), v(2))))
      case Some(RpcMethod.Stop) =>
        if (call.params.isEmpty) Right(Stop())
        else Left(s"${call.name} takes no parameters, got ${describe(call.params)}")
      case Some(RpcMethod.Head) => numbers(call, "pan", "tilt").flatMap(v => checked(Head(v(0), v(1))))
      case Some(RpcMethod.Arms) =>
        numbers(call, "leftShoulder", "leftElbow", "rightShoulder", "rightElbow")
          .flatMap(v => checked(Arms(v(0), v(1), v(2), v(3))))
      case Some(RpcMethod.Posture) =>
        call.params match {
          case Vector(RpcValue.Text(name)) => WirePosture.target(name).flatMap(target => checked(Posture(target)))
          case other =>
            Left(s"${call.name} takes one text (${WirePosture.targets.map(_.name).mkString(", ")}), got " +
              describe(other))
        }
      case Some(RpcMethod.Say) =>
        call.params match {
          case Vector(RpcValue.Text(text)) => checked(Say(text))
          case other                       => Left(s"${call.name} takes one text, got ${describe(other)}")
        }
      case _ => checked(RawCall(call.module, call.method, call.params))
    }
  }

  private def number(v: Double): RpcValue = RpcValue.Number(v.toFloat)

  private def numbers(call: RpcCall, names: String*): Either[String, Vector[Double]] = {
    val values = call.params.collect {
      case RpcValue.Number(f) => f.toDouble
      case RpcValue.UInt(i)   => i.toDouble
    }
    if (call.params.length != names.length || values.length != names.length)
      Left(s"${call.name} takes ${names.length} number(s) (${names.mkString(", ")}), got ${describe(call.params)}")
    else if (values.exists(v => v.isNaN || v.isInfinite)) Left(s"${call.name}: numbers must be finite")
    else Right(values)
  }

  /** Parameters as an error text names them: their kinds, or none. */
  def describe(params: Vector[RpcValue]): String =
    if (params.isEmpty) "none" else params.map(_.productPrefix.toLowerCase).mkString("(", ", ", ")")
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
