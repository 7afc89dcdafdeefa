package robotmiddleware

import scala.concurrent.duration._
import scala.util.{Failure, Success}

import akka.actor.typed.scaladsl.{ActorContext, Behaviors, StashBuffer, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior}
import akka.util.Timeout

import naogateway.access.RobotAccess
import naogateway.api.{CallResult, LinkStats, Priority, RobotEvent, RobotFailure, RobotOnline}
import naogateway.api.{RobotSnapshot, RobotStatusUpdated, VisionFrame}
import naogateway.wire.{ActuatorGroup, Posture, RpcCall, RpcMethod, RpcValue}
import robotmiddleware.GuardState.{BatteryChange, SafetyStep}

/** An app as the middleware knows it: its event ref (its identity), name and priority. */
final case class AppInfo(events: ActorRef[AppEvent], name: String, priority: Int)

/** The middleware's decisions for one robot: leases per actuator group, safety, and the walk kept alive. */
private[robotmiddleware] object RobotGuard {

  /** What a guard accepts. */
  sealed trait Command

  /** Runs an app's operation if the app holds its lease, the robot is online and no safety hold forbids it. */
  final case class Execute(app: AppInfo, operation: Operation, replyTo: ActorRef[CallResult]) extends Command

  /** Sends an app's operation under the same checks as `Execute` and in the same order (one path to the robot's command
    * owner, sent once): `replyTo` learns whether it was accepted; the robot's answer is the guard's alone.
    */
  final case class Send(app: AppInfo, operation: Operation, replyTo: ActorRef[RobotMiddleware.SendResult])
      extends Command

  /** Asks for the leases of a set of actuator groups at the app's priority: all of them or none. */
  final case class Acquire(app: AppInfo, groups: Set[ActuatorGroup], replyTo: ActorRef[RobotMiddleware.LeaseResult])
      extends Command

  /** Gives a lease back. */
  final case class Release(app: ActorRef[AppEvent], group: ActuatorGroup) extends Command

  /** The app's system is gone: release its leases and stop what it left moving. */
  final case class AppGone(app: ActorRef[AppEvent]) extends Command

  /** An online, offline, quality or restart event of this robot. */
  final case class RobotEventReceived(event: RobotEvent) extends Command

  /** Sends the robot's camera frames to `subscriber` (no lease needed). */
  final case class WatchVision(subscriber: ActorRef[VisionFrame], grid: Boolean) extends Command

  /** Sends the robot's link figures to `subscriber` at once and then every `link-stats-interval` (no lease needed). */
  final case class WatchLinkStats(subscriber: ActorRef[LinkStats]) extends Command

  private final case class ChildrenReady(children: RobotAccess.Opened) extends Command
  private final case class SnapshotReceived(snapshot: RobotSnapshot) extends Command
  private final case class OperationDone(
      replyTo: ActorRef[CallResult],
      operation: Operation,
      result: Either[RobotFailure, Option[RpcValue]],
      superseded: Boolean = false
  ) extends Command
  private case object WalkRefresh extends Command
  private case object StatsTick extends Command
  private final case class StatsReceived(stats: LinkStats) extends Command
  private final case class StatsWatcherGone(subscriber: ActorRef[LinkStats]) extends Command
  private final case class VisionWatcherGone(subscriber: ActorRef[VisionFrame]) extends Command
  private final case class SafetyStepDone(step: SafetyStep, result: CallResult) extends Command
  private final case class ChildGone(child: ActorRef[Nothing]) extends Command

  private case object WalkKey
  private case object StatsKey

  /** A guard for `robotId`, whose robot actor is `robot` (narrowed to what the middleware may send it). */
  def apply(robotId: Int, robot: ActorRef[RobotAccess.Command], settings: MiddlewareSettings, online: Boolean,
      holds: ActorRef[RobotHolds]): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        Behaviors.withStash(settings.pendingLimit) { stash =>
          // `online` was right when the guard was first created; after a restart only the robot actor knows.
          robot ! RobotAccess.GetSnapshot(context.messageAdapter(SnapshotReceived.apply))
          val childrenReady = context.messageAdapter(ChildrenReady.apply)
          robot ! RobotAccess.Open(childrenReady)
          val guard = new Guard(robotId, robot, settings, context, timers, stash, childrenReady, holds)
          // A restarted guard starts with no leases and no hold: the middleware's table says so at once.
          val initial = GuardState(online = online)
          guard.report(initial)
          guard.connecting(initial)
        }
      }
    }

  /** The guard's shell: carries out `GuardState`'s transitions (the calls, the timers, the apps' events) and keeps
    * nothing itself.
    */
  private final class Guard(
      robotId: Int,
      robot: ActorRef[RobotAccess.Command],
      settings: MiddlewareSettings,
      context: ActorContext[Command],
      timers: TimerScheduler[Command],
      stash: StashBuffer[Command],
      childrenReady: ActorRef[RobotAccess.Opened],
      holds: ActorRef[RobotHolds]
  ) {

    /** Tells the middleware the lease holders and the safety hold, after each change of either. */
    def report(s: GuardState): Unit = holds ! s.holds(robotId)

    def connecting(s: GuardState): Behavior[Command] = Behaviors.receiveMessage {
      case ChildrenReady(children) =>
        // The refs die with the robot actor's restart (or a child's stop): then the guard connects again.
        Seq[ActorRef[Nothing]](children.response, children.vision).foreach(ref =>
          context.watchWith(ref, ChildGone(ref)))
        // Apps' camera streams: registered again with the new children, whose registrations died with the old ones.
        s.visionWatchers.foreach { case (subscriber, grid) =>
          children.vision ! RobotAccess.RegisterVision(subscriber, grid)
        }
        val next = if (s.reconnectedWhileConnecting) stopAfterReconnect(children, s) else s
        stash.unstashAll(ready(children, next))
      case ChildGone(_) => Behaviors.same // a ref of the children the guard is replacing already
      case e: Execute if !s.online =>
        reply(e.replyTo, e.operation, Left(RobotFailure.RobotOffline(robotId)))
        Behaviors.same
      case m: Send if !s.online =>
        m.replyTo ! RobotMiddleware.SendResult(robotId, m.operation.name, Left(RobotFailure.RobotOffline(robotId)))
        Behaviors.same
      case SnapshotReceived(snapshot) => connecting(s.snapshotReceived(snapshot.online))
      case RobotEventReceived(event)  =>
        // Offline again before the guard is ready: the next RobotOnline, in ready, brings the stop.
        connecting(walkTimer(s, s.eventWhileConnecting(event)))
      case other =>
        if (stash.isFull) other match {
          case e: Execute =>
            reply(e.replyTo, e.operation,
              Left(RobotFailure.Overloaded(robotId, "too many operations wait for the robot")))
          case m: Send =>
            m.replyTo ! RobotMiddleware.SendResult(robotId, m.operation.name,
              Left(RobotFailure.Overloaded(robotId, "too many operations wait for the robot")))
          case a: Acquire =>
            a.replyTo ! RobotMiddleware.LeaseResult(robotId, a.groups, Left(RobotFailure.Overloaded(robotId, "busy")))
          case _ => ()
        }
        else stash.stash(other)
        Behaviors.same
    }

    /** The walk's refresh timer follows the state: a walk forgotten stops being refreshed. */
    private def walkTimer(before: GuardState, after: GuardState): GuardState = {
      if (before.walking.isDefined && after.walking.isEmpty) timers.cancel(WalkKey)
      after
    }

    private def ready(c: RobotAccess.Opened, s: GuardState): Behavior[Command] = Behaviors.receiveMessage {
      // Any event that reached the guard before this answer is older than it, and later ones follow it.
      case SnapshotReceived(snapshot) => ready(c, s.snapshotReceived(snapshot.online))
      case Execute(app, operation, replyTo) =>
        s.refusal(robotId, app, operation, settings.limits) match {
          case Some(refused) =>
            reply(replyTo, operation, Left(refused))
            Behaviors.same
          case None => ready(c, run(c, s, app, operation, replyTo, once = false))
        }
      case Send(app, operation, replyTo) =>
        // Accepted means handed to the command owner below, in this order: the app's next call cannot overtake it.
        s.refusal(robotId, app, operation, settings.limits) match {
          case Some(refused) =>
            replyTo ! RobotMiddleware.SendResult(robotId, operation.name, Left(refused))
            Behaviors.same
          case None =>
            val next = run(c, s, app, operation, context.system.ignoreRef, once = true)
            replyTo ! RobotMiddleware.SendResult(robotId, operation.name, Right(()))
            ready(c, next)
        }
      case Acquire(app, groups, replyTo) =>
        // Checked for every group before any is taken: a set with one group held at equal or higher priority takes
        // nothing, so no app is preempted (and no robot stopped) for a set that is refused.
        s.acquire(app, groups) match {
          case Left((group, holder)) =>
            replyTo ! RobotMiddleware.LeaseResult(robotId, groups,
              Left(RobotFailure.LeaseNotHeld(robotId, group, Some(holder.name))))
            Behaviors.same
          case Right((granted, preempted)) =>
            val next = preempted.foldLeft(granted) { case (st, (group, holder)) =>
              context.log.info("Robot [{}]: lease {} moves from {} to {} (higher priority)", robotId, group.name,
                holder.name, app.name)
              holder.events ! AppEvent.LeasePreempted(robotId, group, app.name)
              if (group == ActuatorGroup.Walk) stopWalking(c, st, s"lease taken by ${app.name}") else st
            }
            // The table first: an app that asks for the holds once granted finds itself in them.
            report(next)
            replyTo ! RobotMiddleware.LeaseResult(robotId, groups, Right(()))
            ready(c, next)
        }
      case Release(app, group) =>
        s.release(app, group) match {
          case None => Behaviors.same
          case Some(released) =>
            report(released)
            ready(c, if (group == ActuatorGroup.Walk) stopWalking(c, released, "lease released") else released)
        }
      case AppGone(app) =>
        val (next, held) = s.appGone(app)
        if (held.isEmpty) Behaviors.same
        else {
          context.log.info("Robot [{}]: app gone, releasing {}", robotId, held.map(_.name).mkString(","))
          report(next)
          ready(c, if (held(ActuatorGroup.Walk)) stopWalking(c, next, "app gone") else next)
        }
      case OperationDone(replyTo, operation, result, superseded) =>
        reply(replyTo, operation, result)
        // A motion that ended in an error must not leave the robot in an undefined motion: stop it.
        // A superseded one is not undefined: the newer call of its slot decides the motion.
        val stopped =
          if (result.isLeft && !superseded && operation.isInstanceOf[Operation.Posture] && s.online)
            stopWalking(c, s, s"${operation.name} failed")
          else s
        val next = operation match {
          case w: Operation.Walk =>
            stopped.walkAnswered(w, result.isRight) match {
              // Refreshing starts only once the robot has confirmed the walk: a refused walk is never sent again.
              case Some((st, true)) =>
                timers.startTimerWithFixedDelay(WalkKey, WalkRefresh, settings.walkRefresh)
                st
              case Some((st, false)) =>
                timers.cancel(WalkKey)
                st
              case None => stopped
            }
          case _ => stopped
        }
        ready(c, next)
      case WalkRefresh =>
        // Through the robot's one command owner, once (no retries): a later stop supersedes it wherever it is.
        s.walking.foreach { case (w, _) =>
          c.response ! RobotAccess.Call(Operation.toCall(w), context.system.ignoreRef, idempotent = Some(false))
        }
        Behaviors.same
      case RobotEventReceived(event) =>
        val (seen, cameBack) = s.eventWhileReady(event)
        val next = walkTimer(s, seen)
        ready(
          c,
          event match {
            case RobotStatusUpdated(snapshot) => snapshot.batteryVoltage.fold(next)(checkBattery(c, next, _))
            // A stop only when the robot really was offline: a stale online event must not supersede an app's motion.
            case RobotOnline(_, _) if cameBack => stopAfterReconnect(c, next)
            case _                             => next
          }
        )
      case SafetyStepDone(step, result) =>
        val (done, sit) = s.safetyStepDone(step)
        val next = result.result match {
          // A newer stop or sit replaced this stop: the robot stops all the same, and the hold still wants it sitting.
          case Right(_) | Left(_: RobotFailure.Superseded) if sit =>
            safetyCall(c, done, SafetyStep.Sit, RpcMethod.Posture.call(RpcValue.Text(Posture.Sit.name)),
              settings.postureTimeout)
          case Left(_: RobotFailure.Superseded) => done // a newer call of the slot took over: nothing failed
          case Left(error) =>
            context.log.warn("Robot [{}]: safety step {} failed: {}", robotId, step.describe, error.describe)
            done
          case Right(_) => done
        }
        ready(c, next)
      case WatchVision(subscriber, grid) =>
        val (next, fresh) = s.visionWatched(subscriber, grid)
        if (fresh) context.watchWith(subscriber, VisionWatcherGone(subscriber))
        c.vision ! RobotAccess.RegisterVision(subscriber, grid)
        ready(c, next)
      case VisionWatcherGone(subscriber) => ready(c, s.visionGone(subscriber))
      case WatchLinkStats(subscriber) =>
        context.watchWith(subscriber, StatsWatcherGone(subscriber))
        if (!timers.isTimerActive(StatsKey))
          timers.startTimerWithFixedDelay(StatsKey, StatsTick, settings.linkStatsInterval)
        // The first figures at once, not one interval later: robotctl status waits for them.
        robot ! RobotAccess.GetLinkStats(statsAdapter)
        ready(c, s.statsWatched(subscriber))
      case StatsWatcherGone(subscriber) =>
        val next = s.statsGone(subscriber)
        if (next.statsWatchers.isEmpty) timers.cancel(StatsKey)
        ready(c, next)
      case StatsTick =>
        robot ! RobotAccess.GetLinkStats(statsAdapter)
        Behaviors.same
      case StatsReceived(stats) =>
        s.statsWatchers.foreach(_ ! stats)
        Behaviors.same
      case ChildrenReady(_) => Behaviors.same
      case ChildGone(child) if child == c.response || child == c.vision =>
        context.log.info("Robot [{}]: its children were restarted; connecting again", robotId)
        // Nothing refreshes the walk meanwhile, so the robot stops by itself within its lease: forget the walk.
        timers.cancel(WalkKey)
        robot ! RobotAccess.Open(childrenReady)
        connecting(s.walkEnded)
      case ChildGone(_) => Behaviors.same
    }

    /** Back from a lost link: puts the robot in a defined state before anyone moves it again. */
    private def stopAfterReconnect(c: RobotAccess.Opened, s: GuardState): GuardState =
      safetyCall(c, s.reconnectStopped, SafetyStep.StopAfterReconnect, RpcMethod.Stop.call(), settings.callTimeout)

    private lazy val statsAdapter = context.messageAdapter[LinkStats](StatsReceived.apply)

    /** `step`, sent now unless the state holds it back (one safety stop in flight at a time). */
    private def safetyCall(c: RobotAccess.Opened, s: GuardState, step: SafetyStep, rpc: RpcCall,
        timeout: FiniteDuration): GuardState = {
      val (next, now) = s.safetyStep(step)
      if (now) askSafety(c, step, rpc, timeout)
      next
    }

    /** One ask per step, not a message adapter: Akka keeps one adapter per message class, so labels would mix. */
    private def askSafety(c: RobotAccess.Opened, step: SafetyStep, rpc: RpcCall, timeout: FiniteDuration): Unit = {
      implicit val askTimeout: Timeout = timeout + settings.askMargin
      context.ask(c.response,
        (ref: ActorRef[CallResult]) => RobotAccess.Call(rpc, ref, Priority.Safety, Some(timeout))) {
        case Success(result) => SafetyStepDone(step, result)
        case Failure(_) => SafetyStepDone(step,
            CallResult(robotId, rpc.name, Left(RobotFailure.Timeout(robotId, rpc.name, (timeout).toMillis))))
      }
    }

    /** A battery reading: a hold that starts stops and sits the robot, and both ends are told to the holders. */
    private def checkBattery(c: RobotAccess.Opened, s: GuardState, volts: Double): GuardState =
      s.batteryRead(volts, settings) match {
        case (next, Some(BatteryChange.HoldStarted(reason))) =>
          context.log.warn("Robot [{}]: {}; stopping and sitting down", robotId, reason)
          report(next)
          next.leases.values.toSet.foreach((holder: AppInfo) => holder.events ! AppEvent.SafetyStop(robotId, reason))
          stopWalking(c, next, reason, thenSit = true)
        case (next, Some(BatteryChange.HoldCleared)) =>
          context.log.info("Robot [{}]: battery back at {} V; motion allowed again", robotId, volts)
          report(next)
          next.leases.values.toSet.foreach((holder: AppInfo) => holder.events ! AppEvent.SafetyCleared(robotId))
          next
        case (next, None) => next
      }

    private def stopWalking(c: RobotAccess.Opened, s: GuardState, why: String, thenSit: Boolean = false): GuardState = {
      if (s.walking.isDefined || thenSit) context.log.info("Robot [{}]: stop ({})", robotId, why)
      timers.cancel(WalkKey)
      safetyCall(c, s.walkEnded, if (thenSit) SafetyStep.StopThenSit else SafetyStep.StopOnly, RpcMethod.Stop.call(),
        settings.callTimeout)
    }

    private def reply(replyTo: ActorRef[CallResult], operation: Operation,
        result: Either[RobotFailure, Option[RpcValue]]): Unit =
      replyTo ! CallResult(robotId, operation.name, result)

    // `once`: a send is sent once (no retries), as the seed's no-response sender does. A walk's or a posture's answer
    // comes back here, so the guard's own bookkeeping (walk refresh, stop after a failed posture) is the same for both
    // doors. Every other operation leaves nothing to keep: the robot's command owner answers its caller directly,
    // which spares each call the hop back through this actor (and the thread it may wake).
    private def call(c: RobotAccess.Opened, operation: Operation, replyTo: ActorRef[CallResult], once: Boolean,
        priority: Priority = Priority.Command, timeout: FiniteDuration = settings.callTimeout): Unit = {
      val idempotent = if (once) Some(false) else None
      val rpc = Operation.toCall(operation)
      operation match {
        case _: Operation.Walk | _: Operation.Posture =>
          implicit val askTimeout: Timeout = timeout + settings.askMargin
          context.ask(c.response,
            (ref: ActorRef[CallResult]) => RobotAccess.Call(rpc, ref, priority, Some(timeout), idempotent)) {
            case Success(result) =>
              OperationDone(replyTo, operation, result.result.left.map(AppFailure(robotId, _)),
                result.result.left.exists(_.isInstanceOf[RobotFailure.Superseded]))
            case Failure(_) =>
              OperationDone(replyTo, operation, Left(RobotFailure.Timeout(robotId, operation.name, timeout.toMillis)))
          }
        case _ => c.response ! RobotAccess.Call(rpc, replyTo, priority, Some(timeout), idempotent)
      }
    }

    private def run(c: RobotAccess.Opened, s: GuardState, app: AppInfo, operation: Operation,
        replyTo: ActorRef[CallResult], once: Boolean): GuardState = operation match {
      case w: Operation.Walk =>
        // The first walk is confirmed by the robot; afterwards the middleware keeps it fresh inside the robot's lease.
        // Until then nothing is refreshed: neither this walk, unconfirmed, nor the one it replaces.
        timers.cancel(WalkKey)
        call(c, operation, replyTo, once)
        s.walkStarted(w, app)
      case Operation.Stop() =>
        timers.cancel(WalkKey)
        call(c, operation, replyTo, once, Priority.Safety)
        s.walkEnded
      case _: Operation.Posture =>
        timers.cancel(WalkKey)
        call(c, operation, replyTo, once, timeout = settings.postureTimeout)
        s.walkEnded
      case r: Operation.RawCall =>
        val timeout = if (RpcMethod.find(r.module, r.method).contains(RpcMethod.Posture)) settings.postureTimeout
        else settings.callTimeout
        call(c, operation, replyTo, once, timeout = timeout)
        s
      case _ =>
        call(c, operation, replyTo, once)
        s
    }
  }
}
