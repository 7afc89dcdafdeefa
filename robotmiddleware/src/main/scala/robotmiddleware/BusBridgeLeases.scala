package robotmiddleware

import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, Behavior}

import naogateway.api.BusBridgeClient
import naogateway.wire.ActuatorGroup

/** The gateway's bus bridge as an app at the middleware (docs/protocol.md 6.9): while a tool is connected to a robot's
  * bridge it holds every actuator lease of that robot at [[BusBridgeLeases.Priority]], so no other app moves the robot
  * during a calibration; it gives them back when the tool leaves.
  */
object BusBridgeLeases {

  /** The app's name at the middleware. */
  val Name: String = "bus-bridge"

  /** Above every app of the demo (ball follower 1, teleop 5): a calibration is not interrupted by them. */
  val Priority: Int = 10

  // The middleware's answers, beside the bridge's client news.
  private final case class Registered(registered: RobotMiddleware.AppRegistered)
  private final case class Leased(result: RobotMiddleware.LeaseResult)

  /** The lease holder at `middleware`; hand the gateway's bridge `ref`'s [[BusBridgeClient]] side. */
  def apply(middleware: ActorRef[RobotMiddleware.Command]): Behavior[BusBridgeClient] =
    Behaviors.setup[Any] { context =>
      // The app's event ref is its identity at the middleware: its leases live as long as it does.
      val events = context.spawn(
        Behaviors.receiveMessage[AppEvent] {
          case AppEvent.LeasePreempted(robotId, group, by) =>
            context.log.warn("Bus bridge: robot {}'s {} lease was taken by {}", robotId, group.name, by)
            Behaviors.same
          case _ => Behaviors.same
        },
        "events"
      )
      middleware ! RobotMiddleware.RegisterApp(Name, Priority, events, context.messageAdapter(Registered.apply))
      Behaviors.receiveMessage[Any] {
        case BusBridgeClient(robotId, true) =>
          middleware ! RobotMiddleware.Acquire(events, robotId, ActuatorGroup.all.toSet,
            context.messageAdapter(Leased.apply))
          Behaviors.same
        case BusBridgeClient(robotId, false) =>
          ActuatorGroup.all.foreach(g => middleware ! RobotMiddleware.Release(events, robotId, g))
          Behaviors.same
        case Leased(RobotMiddleware.LeaseResult(robotId, _, Left(failure))) =>
          context.log.warn("Bus bridge: robot {}'s leases not taken: {}", robotId, failure.getMessage)
          Behaviors.same
        case _ => Behaviors.same
      }
    }.narrow
}
