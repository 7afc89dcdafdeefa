package robotmiddleware

import naogateway.wire.ActuatorGroup

import scala.concurrent.duration._

import akka.actor.typed.receptionist.{Receptionist, ServiceKey}
import akka.actor.typed.scaladsl.{ActorContext, Behaviors}
import akka.actor.typed.{ActorRef, Behavior, DispatcherSelector}

import naogateway.access.{GatewayAccess, RobotAccess}
import naogateway.api.{
  CallResult,
  GameStateUpdated,
  GatewayEvent,
  LinkStats,
  RobotEvent,
  RobotFailure,
  RobotForgotten,
  RobotSnapshot,
  RobotStatusUpdated,
  VisionFrame
}
import naogateway.wire.gamecontroller.GameControlData

/** The one middleware per gateway: apps register here, and every decision about a robot is taken by its guard. */
object RobotMiddleware {

  /** Where apps find the middleware through the receptionist. */
  val ServiceKey: ServiceKey[Command] = akka.actor.typed.receptionist.ServiceKey[Command]("robot-middleware")

  /** What the middleware accepts. */
  sealed trait Command

  /** An app introduces itself; its leases live as long as `events` does. */
  final case class RegisterApp(name: String, priority: Int, events: ActorRef[AppEvent],
      replyTo: ActorRef[AppRegistered])
      extends Command

  /** Runs `operation` on robot `robotId` for the app whose event ref is `app`; `replyTo` gets exactly one `CallResult`,
    * named after the operation. A plain operation's answer comes from the robot's command owner itself (no hop back
    * through the guard), so it may be `Superseded` or `Interrupted`; `RobotInterface` tells apps of both as
    * `Overloaded`.
    */
  final case class Execute(app: ActorRef[AppEvent], robotId: Int, operation: Operation, replyTo: ActorRef[CallResult])
      extends Command

  /** Sends `operation` to robot `robotId` for the app whose event ref is `app`, in the same order as its `Execute`s and
    * through the same checks: `replyTo` learns at once whether it was accepted (lease, online, safety) or refused; the
    * robot's own answer is dropped.
    */
  final case class Send(app: ActorRef[AppEvent], robotId: Int, operation: Operation, replyTo: ActorRef[SendResult])
      extends Command

  /** Asks for the leases of `groups` on robot `robotId` as one: all are granted (preempting lower-priority holders) or,
    * when a holder of equal or higher priority has any of them, none is taken.
    */
  final case class Acquire(app: ActorRef[AppEvent], robotId: Int, groups: Set[ActuatorGroup],
      replyTo: ActorRef[LeaseResult])
      extends Command

  /** The single-group request, kept for callers that take one lease at a time. */
  object Acquire {

    /** Asks for the lease of `group` alone. */
    def apply(app: ActorRef[AppEvent], robotId: Int, group: ActuatorGroup, replyTo: ActorRef[LeaseResult]): Acquire =
      Acquire(app, robotId, Set(group), replyTo)
  }

  /** Gives a lease back. */
  final case class Release(app: ActorRef[AppEvent], robotId: Int, group: ActuatorGroup) extends Command

  /** Answers with every known robot's latest snapshot (the gateway answers, asking its robot actors). */
  final case class ListRobots(replyTo: ActorRef[RobotList]) extends Command

  /** Streams snapshots of one robot (or all) to `subscriber` until it stops, starting with the current ones. */
  final case class WatchStatus(robotId: Option[Int], subscriber: ActorRef[RobotSnapshot]) extends Command

  /** Streams HaViMo2 frames of a robot to `subscriber` (newest only). */
  final case class WatchVision(robotId: Int, subscriber: ActorRef[VisionFrame], grid: Boolean) extends Command

  /** Streams a robot's link figures to `subscriber` at the configured interval. */
  final case class WatchLinkStats(robotId: Int, subscriber: ActorRef[LinkStats]) extends Command

  /** Streams GameController packets to `subscriber`. */
  final case class WatchGame(subscriber: ActorRef[GameControlData]) extends Command

  /** Streams robot events (online, offline, restarts, quality) to `subscriber`. */
  final case class WatchEvents(subscriber: ActorRef[RobotEvent]) extends Command

  /** Answers with every guard's latest lease holders and safety hold. Local to the gateway's node (no cross-node
    * serializer), so the message is private and made here.
    */
  def getHolds(replyTo: ActorRef[Vector[RobotHolds]]): Command = GetHolds(replyTo)

  private final case class GetHolds(replyTo: ActorRef[Vector[RobotHolds]]) extends Command
  private final case class HoldsChanged(holds: RobotHolds) extends Command
  private final case class GatewayEventReceived(event: GatewayEvent) extends Command
  private final case class RobotsListed(replyTo: ActorRef[RobotList], robots: Option[Vector[RobotSnapshot]])
      extends Command
  private final case class StatusKnown(subscriber: ActorRef[RobotSnapshot], robots: Vector[RobotSnapshot])
      extends Command
  private final case class AppTerminated(app: ActorRef[AppEvent]) extends Command
  private final case class WatcherGone(subscriber: ActorRef[Nothing]) extends Command
  private final case class NodeUnreachable(address: akka.actor.Address) extends Command
  private final case class NodeUp(address: akka.actor.Address) extends Command
  private final case class NodeRemoved(address: akka.actor.Address) extends Command
  private final case class HeldExpired(address: akka.actor.Address) extends Command
  private final case class RobotFound(robotId: Int, robot: Option[ActorRef[RobotAccess.Command]], retry: Command)
      extends Command
  private final case class RobotReached(
      robotId: Int, robot: ActorRef[RobotAccess.Command], online: Boolean, retry: Command)
      extends Command

  /** The answer to `RegisterApp`. */
  final case class AppRegistered(name: String)

  /** The one answer every `Send` gets: accepted (`Right`) once the robot's command owner has it, or the refusal. */
  final case class SendResult(robotId: Int, operation: String, result: Either[RobotFailure, Unit])

  /** The answer to `ListRobots`: every known robot's latest snapshot (a named type, so nodes bind no library class). */
  final case class RobotList(robots: Vector[RobotSnapshot])

  /** The answer to `Acquire`, for the groups it asked for together (a refusal's `LeaseNotHeld` names the one in
    * conflict).
    */
  final case class LeaseResult(robotId: Int, groups: Set[ActuatorGroup], result: Either[RobotFailure, Unit])

  /** The single-group answer, kept for callers that take one lease at a time. */
  object LeaseResult {

    /** The answer for `group` alone. */
    def apply(robotId: Int, group: ActuatorGroup, result: Either[RobotFailure, Unit]): LeaseResult =
      LeaseResult(robotId, Set(group), result)
  }

  /** Where the middleware and its guards run (`robotmiddleware.dispatcher`): spawn the middleware with it. */
  def dispatcher(settings: MiddlewareSettings): DispatcherSelector = DispatcherSelector.fromConfig(settings.dispatcher)

  /** The middleware in front of `gateway`, registered with the receptionist. It holds the gateway's middleware view and
    * each robot's `RobotAccess.Command`: it can reach a robot only through the robot's response and vision actors.
    */
  def apply(gateway: ActorRef[GatewayAccess.Command], settings: MiddlewareSettings): Behavior[Command] =
    Behaviors.setup { context =>
      context.system.receptionist ! Receptionist.Register(ServiceKey, context.self)
      gateway ! GatewayAccess.Subscribe(context.messageAdapter(GatewayEventReceived.apply))
      val clustered = context.system.settings.config.getString("akka.actor.provider") == "cluster"
      if (clustered) {
        import akka.cluster.ClusterEvent.{MemberRemoved, MemberUp, MemberWeaklyUp, UnreachableMember}
        val cluster = akka.cluster.typed.Cluster(context.system)
        // An app whose node becomes unreachable loses its robots at once, not only when the node is downed seconds
        // later: a blind app must not keep a robot walking.
        val unreachable = context.messageAdapter[UnreachableMember](e => NodeUnreachable(e.member.address))
        cluster.subscriptions ! akka.cluster.typed.Subscribe(unreachable, classOf[UnreachableMember])
        // The nodes Akka's death watch knows: it drops the watch of an actor on a node this one has not yet seen Up
        // (the cluster's remote watcher takes members from MemberUp and MemberWeaklyUp, and forgets them removed).
        cluster.subscriptions ! akka.cluster.typed.Subscribe(
          context.messageAdapter[MemberUp](e => NodeUp(e.member.address)), classOf[MemberUp])
        cluster.subscriptions ! akka.cluster.typed.Subscribe(
          context.messageAdapter[MemberWeaklyUp](e => NodeUp(e.member.address)), classOf[MemberWeaklyUp])
        cluster.subscriptions ! akka.cluster.typed.Subscribe(
          context.messageAdapter[MemberRemoved](e => NodeRemoved(e.member.address)), classOf[MemberRemoved])
      }
      new Middleware(gateway, settings, context, clustered).running()
    }

  /** How many watch requests of one node that is not yet Up the middleware keeps until it is, and for how long. */
  private val HeldPerNode = 64
  private val HeldFor: FiniteDuration = 30.seconds

  /** A node's watch requests waiting for it to come up, and how many more it sent than were kept. */
  private final case class Held(requests: Vector[Command], dropped: Int)

  private final class Middleware(gateway: ActorRef[GatewayAccess.Command], settings: MiddlewareSettings,
      context: ActorContext[Command], clustered: Boolean) {
    private var apps = Map.empty[ActorRef[AppEvent], AppInfo]
    // No copy of any robot's state here: snapshots and online belong to the robot actors; this actor asks or forwards.
    private var guards = Map.empty[Int, ActorRef[RobotGuard.Command]]
    private var statusWatchers = Map.empty[ActorRef[RobotSnapshot], Option[Int]]
    private var gameWatchers = Set.empty[ActorRef[GameControlData]]
    private var eventWatchers = Set.empty[ActorRef[RobotEvent]]
    // What each guard last reported of its leases and safety hold: the guards' state, for robotctl's status and doctor.
    private var holds = Map.empty[Int, RobotHolds]
    private lazy val holdsAdapter = context.messageAdapter[RobotHolds](HoldsChanged.apply)

    private def guard(
        robotId: Int, robot: ActorRef[RobotAccess.Command], online: Boolean): ActorRef[RobotGuard.Command] =
      guards.getOrElse(
        robotId, {
          val g = context.spawn(
            Behaviors.supervise(RobotGuard(robotId, robot, settings, online, holdsAdapter))
              .onFailure(settings.guardRestart.strategy),
            s"guard-$robotId",
            dispatcher(settings)
          )
          guards = guards.updated(robotId, g)
          g
        }
      )

    // Nodes Up (or weakly up) as this node's cluster sees them, and the watch requests of nodes not yet Up.
    private var upNodes = Set.empty[akka.actor.Address]
    private var held = Map.empty[akka.actor.Address, Held]
    private val selfAddress = context.system.address

    /** The ref a request asks the middleware (or a guard, or the robot actor behind it) to death-watch. */
    private def watched(command: Command): Option[ActorRef[Nothing]] = command match {
      case RegisterApp(_, _, events, _)  => Some(events)
      case WatchStatus(_, subscriber)    => Some(subscriber)
      case WatchVision(_, subscriber, _) => Some(subscriber)
      case WatchLinkStats(_, subscriber) => Some(subscriber)
      case WatchGame(subscriber)         => Some(subscriber)
      case WatchEvents(subscriber)       => Some(subscriber)
      case _                             => None
    }

    /** A request to watch a ref on a node that is not yet Up here waits until it is: Akka would drop the watch and
      * never tell of the ref's end (an ended camera stream would keep the camera on, a closed session its leases). Its
      * node's last requests beyond [[HeldPerNode]] are dropped, and all of them after [[HeldFor]] without the node Up.
      */
    private def heldBack(command: Command): Boolean =
      watched(command).map(_.path.address).filterNot { address =>
        !clustered || address.hasLocalScope || address == selfAddress || upNodes(address)
      } match {
        case None => false
        case Some(address) =>
          val waiting = held.getOrElse(address, {
              context.scheduleOnce(HeldFor, context.self, HeldExpired(address))
              Held(Vector.empty, 0)
            })
          if (waiting.dropped == 0 && waiting.requests.size == HeldPerNode)
            context.log.warn("Node [{}] is not up yet and asks for more than {} watches: dropping more", address,
              HeldPerNode)
          held = held.updated(address,
            if (waiting.requests.size < HeldPerNode) waiting.copy(requests = waiting.requests :+ command)
            else waiting.copy(dropped = waiting.dropped + 1))
          true
      }

    private implicit val lookupTimeout: akka.util.Timeout = akka.util.Timeout(settings.lookupTimeout)

    /** Hands `command` to the robot's guard, first finding the robot at the gateway when there is no guard yet. */
    private def withGuard(robotId: Int, command: Command)(use: ActorRef[RobotGuard.Command] => Unit): Unit =
      guards.get(robotId) match {
        case Some(g) => use(g)
        case None =>
          val ask = (ref: ActorRef[Option[ActorRef[RobotAccess.Command]]]) => GatewayAccess.GetRobotAccess(robotId, ref)
          context.ask(gateway, ask) {
            case scala.util.Success(found) => RobotFound(robotId, found, command)
            case scala.util.Failure(_)     => RobotFound(robotId, None, command)
          }
      }

    private def unknownApp(app: ActorRef[AppEvent]): AppInfo = AppInfo(app, s"unregistered app ${app.path.name}", 0)

    def running(): Behavior[Command] = Behaviors.receiveMessage { command =>
      if (!heldBack(command)) serve(command)
      Behaviors.same
    }

    /** What `command` asks, now: its watched ref (if any) is on a node death watch knows. */
    private def serve(command: Command): Unit = command match {
      case NodeUp(address) =>
        upNodes += address
        held.get(address).foreach { waiting =>
          held -= address
          waiting.requests.foreach(serve)
        }
      case NodeRemoved(address) =>
        upNodes -= address
        held -= address
      case HeldExpired(address) =>
        held.get(address).foreach { waiting =>
          context.log.warn("Node [{}] did not come up within {}: dropped its {} watch requests", address, HeldFor,
            waiting.requests.size + waiting.dropped)
        }
        held -= address
      case RegisterApp(name, priority, events, replyTo) =>
        context.log.info("App [{}] registered with priority {}", name, priority)
        context.watchWith(events, AppTerminated(events))
        apps = apps.updated(events, AppInfo(events, name, priority))
        replyTo ! AppRegistered(name)
      case c @ Execute(app, robotId, operation, replyTo) =>
        withGuard(robotId, c)(_ ! RobotGuard.Execute(apps.getOrElse(app, unknownApp(app)), operation, replyTo))
      case c @ Send(app, robotId, operation, replyTo) =>
        withGuard(robotId, c)(_ ! RobotGuard.Send(apps.getOrElse(app, unknownApp(app)), operation, replyTo))
      case c @ Acquire(app, robotId, groups, replyTo) =>
        withGuard(robotId, c)(_ ! RobotGuard.Acquire(apps.getOrElse(app, unknownApp(app)), groups, replyTo))
      case Release(app, robotId, group) =>
        guards.get(robotId).foreach(_ ! RobotGuard.Release(app, group))
      case c @ WatchVision(robotId, subscriber, grid) =>
        withGuard(robotId, c)(_ ! RobotGuard.WatchVision(subscriber, grid))
      case c @ WatchLinkStats(robotId, subscriber) =>
        withGuard(robotId, c)(_ ! RobotGuard.WatchLinkStats(subscriber))
      case RobotFound(robotId, Some(robot), command) =>
        if (guards.contains(robotId)) context.self ! command
        else
          // The new guard must know at once whether the robot is online (an Execute may reach it before its own
          // question to the robot is answered); the robot actor, which owns that, is asked.
          context.ask(robot, RobotAccess.GetSnapshot.apply) {
            case scala.util.Success(snapshot) => RobotReached(robotId, robot, snapshot.online, command)
            case scala.util.Failure(_)        => RobotReached(robotId, robot, online = false, command)
          }
      case RobotReached(robotId, robot, online, command) =>
        guard(robotId, robot, online)
        context.self ! command
      case RobotFound(robotId, None, command) =>
        command match {
          case Execute(_, _, operation, replyTo) =>
            replyTo ! CallResult(robotId, operation.name, Left(RobotFailure.UnknownRobot(robotId)))
          case Send(_, _, operation, replyTo) =>
            replyTo ! SendResult(robotId, operation.name, Left(RobotFailure.UnknownRobot(robotId)))
          case Acquire(_, _, groups, replyTo) =>
            replyTo ! LeaseResult(robotId, groups, Left(RobotFailure.UnknownRobot(robotId)))
          case _ => context.log.info("Watch request for unknown robot [{}] ignored", robotId)
        }
      case GetHolds(replyTo) =>
        replyTo ! holds.values.toVector.sortBy(_.robotId)
      case HoldsChanged(h) =>
        if (guards.contains(h.robotId)) holds = holds.updated(h.robotId, h)
      case ListRobots(replyTo) =>
        // A gateway that does not answer leaves the app's own ask to time out, which the facade reports as a Timeout.
        context.ask(gateway, GatewayAccess.GetRobots.apply) {
          case scala.util.Success(robots) => RobotsListed(replyTo, Some(robots))
          case scala.util.Failure(_)      => RobotsListed(replyTo, None)
        }
      case RobotsListed(replyTo, robots) =>
        robots.foreach(replyTo ! RobotList(_))
      case WatchStatus(robotId, subscriber) =>
        context.watchWith(subscriber, WatcherGone(subscriber))
        statusWatchers = statusWatchers.updated(subscriber, robotId)
        // The current snapshots first, asked of the gateway; keep-alives follow as they arrive.
        context.ask(gateway, GatewayAccess.GetRobots.apply)(tried =>
          StatusKnown(subscriber, tried.getOrElse(Vector.empty)))
      case StatusKnown(subscriber, robots) =>
        statusWatchers.get(subscriber).foreach(filter =>
          robots.filter(s => filter.forall(_ == s.robotId)).foreach(subscriber ! _))
      case WatchGame(subscriber) =>
        context.watchWith(subscriber, WatcherGone(subscriber))
        gameWatchers += subscriber
      case WatchEvents(subscriber) =>
        context.watchWith(subscriber, WatcherGone(subscriber))
        eventWatchers += subscriber
      case WatcherGone(subscriber) =>
        statusWatchers = statusWatchers.filterNot(_._1 == subscriber)
        gameWatchers = gameWatchers.filterNot(_ == subscriber)
        eventWatchers = eventWatchers.filterNot(_ == subscriber)
      case NodeUnreachable(address) =>
        val gone = apps.keys.filter(_.path.address == address)
        gone.foreach { app =>
          context.log.warn("App [{}] is unreachable: releasing its leases and stopping its robots", apps(app).name)
          apps -= app
          guards.values.foreach(_ ! RobotGuard.AppGone(app))
        }
      case AppTerminated(app) =>
        context.log.info("App [{}] is gone: releasing its leases and stopping its robots",
          apps.get(app).map(_.name).getOrElse("?"))
        apps -= app
        guards.values.foreach(_ ! RobotGuard.AppGone(app))
      case GatewayEventReceived(event) =>
        event match {
          case e: RobotEvent =>
            e match {
              case RobotStatusUpdated(s) => statusWatchers.foreach { case (w, filter) =>
                  if (filter.forall(_ == s.robotId)) w ! s
                }
              case _ => ()
            }
            e match {
              case RobotForgotten(robotId, _) =>
                // The gateway forgot a robot the network introduced: its guard goes too, so no map here outlives it.
                guards.get(robotId).foreach(context.stop(_))
                guards -= robotId
                holds -= robotId
              case _ => guards.get(e.robotId).foreach(_ ! RobotGuard.RobotEventReceived(e))
            }
            if (!e.isInstanceOf[RobotStatusUpdated]) eventWatchers.foreach(_ ! e)
          case GameStateUpdated(data) => gameWatchers.foreach(_ ! data)
        }
    }
  }
}
