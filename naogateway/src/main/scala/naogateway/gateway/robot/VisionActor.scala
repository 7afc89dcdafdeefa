package naogateway.gateway.robot

import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, Behavior}

import naogateway.proto.{DebuggingCommands, DebuggingOptionNames}
import naogateway.access.RobotAccess
import naogateway.api.VisionFrame

/** HaViMo2 frames of one robot, fanned out newest-only to any number of stream subscribers. */
object VisionActor {

  /** What the vision actor takes from its robot actor, and the middleware's [[RobotAccess.RegisterVision]] wrapped into
    * [[Registering]] as it arrives.
    */
  private[naogateway] sealed trait Command

  /** A frame arrived from the robot. */
  private[naogateway] final case class FrameReceived(frame: VisionFrame) extends Command

  /** A subscriber's registration, handed on to the robot actor, which keeps the registrations. */
  private[naogateway] final case class Registering(registration: RobotAccess.RegisterVision) extends Command

  /** The robot actor's registrations now, subscriber to whether it wants grid frames: on every change and every start.
    */
  private[naogateway] final case class Subscribers(subscribers: Map[ActorRef[VisionFrame], Boolean]) extends Command

  /** The robot restarted: switch the camera options on again if anyone is watching. */
  private[naogateway] case object Resync extends Command

  val RegionsOption: String = "havimo.regions"
  val GridOption: String = "havimo.grid"

  /** A vision actor for robot `robotId`, switching camera options through `robot`, which owns the registrations: a new
    * incarnation asks it for them before it forwards any frame. Spawned as both its protocols: a registration is
    * wrapped into its own as it arrives.
    */
  private[naogateway] def apply(robotId: Int, robot: ActorRef[RobotActor.FromChild]): Behavior[Any] =
    Behaviors.setup[Command] { context =>
      robot ! RobotActor.VisionSubscribersWanted(context.self)

      def options(subscribers: Map[ActorRef[VisionFrame], Boolean]): Set[String] =
        if (subscribers.isEmpty) Set.empty
        else Set(RegionsOption) ++ (if (subscribers.values.exists(identity)) Set(GridOption) else Set.empty)

      def send(cmd: DebuggingCommands): Unit =
        robot ! RobotActor.OptionCommand(cmd)

      def switch(from: Set[String], to: Set[String]): Unit = {
        val on = to -- from
        val off = from -- to
        if (on.nonEmpty || off.nonEmpty) {
          context.log.debug("Robot [{}]: camera options on {} off {}", robotId, on.mkString(","), off.mkString(","))
          // One field per DebuggingCommands message (protocol.md 6.3): enabling and disabling are two messages.
          if (on.nonEmpty) send(DebuggingCommands(optionEnable = Some(DebuggingOptionNames(on.toSeq.sorted))))
          if (off.nonEmpty) send(DebuggingCommands(optionDisable = Some(DebuggingOptionNames(off.toSeq.sorted))))
        }
      }

      def running(subscribers: Map[ActorRef[VisionFrame], Boolean]): Behavior[Command] = Behaviors.receiveMessage {
        case FrameReceived(frame) =>
          frame match {
            case _: VisionFrame.Regions => subscribers.keys.foreach(_ ! frame)
            case _: VisionFrame.Grid    => subscribers.foreach { case (s, grid) => if (grid) s ! frame }
          }
          Behaviors.same
        case Registering(RobotAccess.RegisterVision(subscriber, grid)) =>
          robot ! RobotActor.VisionSubscribe(subscriber, grid)
          Behaviors.same
        case Subscribers(next) =>
          // A new incarnation starts from none: the options its predecessor switched on are enabled again, which the
          // robot takes as a no-op.
          switch(options(subscribers), options(next))
          running(next)
        case Resync =>
          switch(Set.empty, options(subscribers))
          Behaviors.same
      }

      running(Map.empty)
    }.transformMessages[Any] {
      case registration: RobotAccess.RegisterVision => Registering(registration)
      case own: Command                             => own
    }
}
