package robotmiddleware

import naogateway.wire.ActuatorGroup

import scala.concurrent.duration._
import scala.util.{Failure, Success}

import akka.actor.typed.scaladsl.{ActorContext, Behaviors, StashBuffer, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior}
import akka.util.Timeout

import naogateway.access.RobotAccess
import naogateway.api.{
  CallResult,
  LinkStats,
  Priority,
  RobotEvent,
  RobotFailure,
  RobotOffline,
  RobotOnline,
  RobotSnapshot,
  RobotStatusUpdated,
  VisionFrame
}
import naogateway.wire.{Posture, RpcCall, RpcMethod, RpcValue}

/** How apps are told of a call that a newer one replaced or a restart interrupted: as an overload to retry, the one
  * error type, in words for apps. Applied by the guard to the answers it relays and by `RobotInterface` to those the
  * robot's command owner sends an app directly.
  */
private[robotmiddleware] object AppFailure {

  /** `error` as an app sees it. */
  def apply(robotId: Int, error: RobotFailure): RobotFailure = error match {
    case RobotFailure.Superseded(_, call)  => RobotFailure.Overloaded(robotId, s"$call replaced by a newer one")
    case RobotFailure.Interrupted(_, call) => RobotFailure.Overloaded(robotId, s"$call interrupted, try again")
    case other                             => other
  }
}

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

  /** The guard's own calls that keep a robot safe; each one's answer comes back with its own step. */
  private sealed abstract class SafetyStep(val describe: String) extends Product with Serializable
  private object SafetyStep {

    /** The stop of a safety hold, followed by a sit once the robot has stopped. */
    case object StopThenSit extends SafetyStep("stop")

    /** A stop that ends a walk (lease released or taken, app gone, a motion failed). */
    case object StopOnly extends SafetyStep("stop only")

    /** The stop a robot gets when it comes back online. */
    case object StopAfterReconnect extends SafetyStep("stop after reconnect")

    /** The sit of a safety hold. */
    case object Sit extends SafetyStep("sit")
  }

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
          guard.report()
          guard.connecting(online)
        }
      }
    }

  /** The reason of a battery hold, with how it ends: what `SafetyStop`, `SafetyHold` and `robotctl doctor` say. */
  def batteryLow(volts: Double, readings: Int, settings: MiddlewareSettings): String =
    f"battery low: $volts%.2f V or less for $readings keep-alives (below ${settings.lowBattery}%.2f V); it clears " +
      f"by itself once $readings keep-alives in a row read above ${settings.batteryOk}%.2f V: swap or charge the " +
      "battery (a simulated robot recharges while it sits; `robotctl battery <id> swap` swaps its battery at once)"

  /** The lease table: holder per group. */
  private type Leases = Map[ActuatorGroup, AppInfo]

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
    private var leases: Leases = Map.empty

    /** Tells the middleware the lease holders and the safety hold, after each change of either. */
    def report(): Unit = holds ! RobotHolds(robotId, leases.map { case (g, app) => g -> app.name }, safety)

    private var walking: Option[(Operation.Walk, AppInfo)] = None
    private var safety: Option[String] = None
    private var online = false
    // A robot that came back while the guard was still connecting gets its reconnect stop once the guard is ready.
    private var reconnectedWhileConnecting = false
    private var statsWatchers = Set.empty[ActorRef[LinkStats]]
    // Apps' camera streams: registered again with the new children after the robot actor restarted, whose
    // registrations died with it.
    private var visionWatchers = Map.empty[ActorRef[VisionFrame], Boolean]

    def connecting(initiallyOnline: Boolean): Behavior[Command] = {
      online = initiallyOnline
      Behaviors.receiveMessage {
        case ChildrenReady(children) =>
          // The refs die with the robot actor's restart (or a child's stop): then the guard connects again.
          Seq[ActorRef[Nothing]](children.response, children.vision).foreach(ref =>
            context.watchWith(ref, ChildGone(ref)))
          visionWatchers.foreach { case (subscriber, grid) =>
            children.vision ! RobotAccess.RegisterVision(subscriber, grid)
          }
          if (reconnectedWhileConnecting) stopAfterReconnect(children)
          stash.unstashAll(ready(children))
        case ChildGone(_) => Behaviors.same // a ref of the children the guard is replacing already
        case e: Execute if !online =>
          reply(e.replyTo, e.operation, Left(RobotFailure.RobotOffline(robotId)))
          Behaviors.same
        case s: Send if !online =>
          s.replyTo ! RobotMiddleware.SendResult(robotId, s.operation.name, Left(RobotFailure.RobotOffline(robotId)))
          Behaviors.same
        case SnapshotReceived(snapshot) =>
          online = snapshot.online
          Behaviors.same
        case RobotEventReceived(event) =>
          val wasOnline = online
          common(event)
          event match {
            // Only a robot the guard saw offline has come back; an online event older than its snapshot has not.
            case RobotOnline(_, _) => if (!wasOnline) reconnectedWhileConnecting = true
            // Offline again before the guard is ready: the next RobotOnline, in ready, brings the stop.
            case RobotOffline(_, _) => reconnectedWhileConnecting = false
            case _                  => ()
          }
          Behaviors.same
        case other =>
          if (stash.isFull) other match {
            case e: Execute =>
              reply(e.replyTo, e.operation,
                Left(RobotFailure.Overloaded(robotId, "too many operations wait for the robot")))
            case s: Send =>
              s.replyTo ! RobotMiddleware.SendResult(robotId, s.operation.name,
                Left(RobotFailure.Overloaded(robotId, "too many operations wait for the robot")))
            case a: Acquire =>
              a.replyTo ! RobotMiddleware.LeaseResult(robotId, a.groups, Left(RobotFailure.Overloaded(robotId, "busy")))
            case _ => ()
          }
          else stash.stash(other)
          Behaviors.same
      }
    }

    /** Events that change the guard's view in any state. */
    private def common(event: RobotEvent): Unit = event match {
      case RobotOnline(_, _) => online = true
      case RobotOffline(_, _) =>
        online = false
        // The robot's own walk lease stops it; the middleware forgets the walk so it is not resumed by surprise.
        if (walking.isDefined) {
          timers.cancel(WalkKey)
          walking = None
        }
      case _ => ()
    }

    private def ready(c: RobotAccess.Opened): Behavior[Command] = Behaviors.receiveMessage {
      case SnapshotReceived(snapshot) =>
        // Any event that reached the guard before this answer is older than it, and later ones follow it.
        online = snapshot.online
        Behaviors.same
      case Execute(app, operation, replyTo) =>
        refusal(app, operation) match {
          case Some(refused) => reply(replyTo, operation, Left(refused))
          case None          => run(c, app, operation, replyTo, once = false)
        }
        Behaviors.same
      case Send(app, operation, replyTo) =>
        // Accepted means handed to the command owner below, in this order: the app's next call cannot overtake it.
        refusal(app, operation) match {
          case Some(refused) => replyTo ! RobotMiddleware.SendResult(robotId, operation.name, Left(refused))
          case None =>
            run(c, app, operation, context.system.ignoreRef, once = true)
            replyTo ! RobotMiddleware.SendResult(robotId, operation.name, Right(()))
        }
        Behaviors.same
      case Acquire(app, groups, replyTo) =>
        // Checked for every group before any is taken: a set with one group held at equal or higher priority takes
        // nothing, so no app is preempted (and no robot stopped) for a set that is refused. The first conflict in
        // the docs' group order is named, so the answer does not depend on a Set's iteration order.
        val conflict = ActuatorGroup.all.filter(groups).flatMap { group =>
          leases.get(group).filter(holder => holder.events != app.events && holder.priority >= app.priority).map(
            group -> _)
        }.headOption
        conflict match {
          case Some((group, holder)) =>
            replyTo ! RobotMiddleware.LeaseResult(robotId, groups,
              Left(RobotFailure.LeaseNotHeld(robotId, group, Some(holder.name))))
          case None =>
            ActuatorGroup.all.filter(groups).foreach { group =>
              leases.get(group).filter(_.events != app.events).foreach { holder =>
                context.log.info("Robot [{}]: lease {} moves from {} to {} (higher priority)", robotId, group.name,
                  holder.name, app.name)
                holder.events ! AppEvent.LeasePreempted(robotId, group, app.name)
                if (group == ActuatorGroup.Walk) stopWalking(c, s"lease taken by ${app.name}")
              }
              leases = leases.updated(group, app)
            }
            // The table first: an app that asks for the holds once granted finds itself in them.
            report()
            replyTo ! RobotMiddleware.LeaseResult(robotId, groups, Right(()))
        }
        Behaviors.same
      case Release(app, group) =>
        if (leases.get(group).exists(_.events == app)) {
          leases -= group
          report()
          if (group == ActuatorGroup.Walk) stopWalking(c, "lease released")
        }
        Behaviors.same
      case AppGone(app) =>
        val held = leases.collect { case (g, holder) if holder.events == app => g }
        if (held.nonEmpty) {
          context.log.info("Robot [{}]: app gone, releasing {}", robotId, held.map(_.name).mkString(","))
          leases --= held
          report()
          if (held.exists(_ == ActuatorGroup.Walk)) stopWalking(c, "app gone")
        }
        Behaviors.same
      case OperationDone(replyTo, operation, result, superseded) =>
        reply(replyTo, operation, result)
        // A motion that ended in an error must not leave the robot in an undefined motion: stop it.
        // A superseded one is not undefined: the newer call of its slot decides the motion.
        if (result.isLeft && !superseded && operation.isInstanceOf[Operation.Posture] && online)
          stopWalking(c, s"${operation.name} failed")
        operation match {
          case w: Operation.Walk if walking.exists(_._1 == w) =>
            // Refreshing starts only once the robot has confirmed the walk: a refused walk is never sent again.
            if (result.isRight) timers.startTimerWithFixedDelay(WalkKey, WalkRefresh, settings.walkRefresh)
            else {
              timers.cancel(WalkKey)
              walking = None
            }
          case _ => ()
        }
        Behaviors.same
      case WalkRefresh =>
        // Through the robot's one command owner, once (no retries): a later stop supersedes it wherever it is.
        walking.foreach { case (w, _) =>
          c.response ! RobotAccess.Call(walkCall(w), context.system.ignoreRef, idempotent = Some(false))
        }
        Behaviors.same
      case RobotEventReceived(event) =>
        val wasOnline = online
        common(event)
        event match {
          case RobotStatusUpdated(snapshot) => checkBattery(c, snapshot)
          // A stop only when the robot really was offline: a stale online event must not supersede an app's motion.
          case RobotOnline(_, _) => if (!wasOnline) stopAfterReconnect(c)
          case _                 => ()
        }
        Behaviors.same
      case SafetyStepDone(step, result) =>
        val wantsSit = step == SafetyStep.StopThenSit || (isStop(step) && sitAfterStop)
        if (isStop(step)) { stopInFlight = false; sitAfterStop = false }
        result.result match {
          // A newer stop or sit replaced this stop: the robot stops all the same, and the hold still wants it sitting.
          case Right(_) | Left(_: RobotFailure.Superseded) if wantsSit && safety.isDefined =>
            safetyCall(c, SafetyStep.Sit, RpcMethod.Posture.call(RpcValue.Text(Posture.Sit.name)),
              settings.postureTimeout)
          case Left(_: RobotFailure.Superseded) => () // a newer call of the slot took over: nothing failed
          case Left(error) =>
            context.log.warn("Robot [{}]: safety step {} failed: {}", robotId, step.describe, error.describe)
          case Right(_) => ()
        }
        Behaviors.same
      case WatchVision(subscriber, grid) =>
        if (!visionWatchers.contains(subscriber)) context.watchWith(subscriber, VisionWatcherGone(subscriber))
        visionWatchers = visionWatchers.updated(subscriber, grid)
        c.vision ! RobotAccess.RegisterVision(subscriber, grid)
        Behaviors.same
      case VisionWatcherGone(subscriber) =>
        visionWatchers -= subscriber
        Behaviors.same
      case WatchLinkStats(subscriber) =>
        context.watchWith(subscriber, StatsWatcherGone(subscriber))
        statsWatchers += subscriber
        if (!timers.isTimerActive(StatsKey))
          timers.startTimerWithFixedDelay(StatsKey, StatsTick, settings.linkStatsInterval)
        // The first figures at once, not one interval later: robotctl status waits for them.
        robot ! RobotAccess.GetLinkStats(statsAdapter)
        Behaviors.same
      case StatsWatcherGone(subscriber) =>
        statsWatchers -= subscriber
        if (statsWatchers.isEmpty) timers.cancel(StatsKey)
        Behaviors.same
      case StatsTick =>
        robot ! RobotAccess.GetLinkStats(statsAdapter)
        Behaviors.same
      case StatsReceived(stats) =>
        statsWatchers.foreach(_ ! stats)
        Behaviors.same
      case ChildrenReady(_) => Behaviors.same
      case ChildGone(child) if child == c.response || child == c.vision =>
        context.log.info("Robot [{}]: its children were restarted; connecting again", robotId)
        // Nothing refreshes the walk meanwhile, so the robot stops by itself within its lease: forget the walk.
        timers.cancel(WalkKey)
        walking = None
        robot ! RobotAccess.Open(childrenReady)
        connecting(online)
      case ChildGone(_) => Behaviors.same
    }

    /** Back from a lost link: puts the robot in a defined state before anyone moves it again. */
    private def stopAfterReconnect(c: RobotAccess.Opened): Unit = {
      reconnectedWhileConnecting = false
      safetyCall(c, SafetyStep.StopAfterReconnect, RpcMethod.Stop.call(), settings.callTimeout)
    }

    private lazy val statsAdapter = context.messageAdapter[LinkStats](StatsReceived.apply)

    /** One ask per step, not a message adapter: Akka keeps one adapter per message class, so labels would mix. */
    // One safety stop in flight at a time (the response actor resends it with new call ids when it is lost): events
    // anyone can provoke (a robot coming back, a battery reading) cannot be turned into a flood of stops. A hold that
    // wants the robot sitting while a stop is in flight sits once that stop is answered.
    private var stopInFlight = false
    private var sitAfterStop = false

    private def isStop(step: SafetyStep): Boolean =
      step == SafetyStep.StopThenSit || step == SafetyStep.StopOnly || step == SafetyStep.StopAfterReconnect

    private def safetyCall(c: RobotAccess.Opened, step: SafetyStep, rpc: RpcCall, timeout: FiniteDuration): Unit =
      if (isStop(step) && stopInFlight) {
        if (step == SafetyStep.StopThenSit) sitAfterStop = true
      } else {
        if (isStop(step)) stopInFlight = true
        askSafety(c, step, rpc, timeout)
      }

    private def askSafety(c: RobotAccess.Opened, step: SafetyStep, rpc: RpcCall, timeout: FiniteDuration): Unit = {
      implicit val askTimeout: Timeout = timeout + settings.askMargin
      context.ask(c.response,
        (ref: ActorRef[CallResult]) => RobotAccess.Call(rpc, ref, Priority.Safety, Some(timeout))) {
        case Success(result) => SafetyStepDone(step, result)
        case Failure(_) => SafetyStepDone(step,
            CallResult(robotId, rpc.name, Left(RobotFailure.Timeout(robotId, rpc.name, (timeout).toMillis))))
      }
    }

    /** Why an app's operation may not run now (an argument out of range, offline, lease, safety), the same for both
      * doors.
      */
    private def refusal(app: AppInfo, operation: Operation): Option[RobotFailure] = {
      val group = operation.group
      val held = group.forall(g => leases.get(g).exists(_.events == app.events))
      val outOfRange = settings.limits.check(operation)
      if (outOfRange.isDefined) Some(RobotFailure.RobotError(robotId, outOfRange.get))
      else if (!online) Some(RobotFailure.RobotOffline(robotId))
      else if (!held) Some(RobotFailure.LeaseNotHeld(robotId, group.get, group.flatMap(leases.get).map(_.name)))
      else if (safety.isDefined && refusedWhenUnsafe(operation)) Some(RobotFailure.SafetyHold(robotId, safety.get))
      else None
    }

    private def refusedWhenUnsafe(operation: Operation): Boolean = operation match {
      case _: Operation.Walk | _: Operation.Arms => true
      case Operation.Posture(p)                  => p != Posture.Sit
      case r: Operation.RawCall =>
        (r.group.contains(ActuatorGroup.Walk) && !RpcMethod.find(r.module, r.method).contains(RpcMethod.Stop) &&
          !(RpcMethod.find(r.module, r.method).contains(RpcMethod.Posture) && r.params == Vector(
            RpcValue.Text(Posture.Sit.name)))) ||
        r.group.contains(ActuatorGroup.Arms)
      case _ => false
    }

    // The latest battery readings, at most `batteryReadings` of them: the hold acts on a sustained reading only.
    private var readings = Vector.empty[Double]

    private def checkBattery(c: RobotAccess.Opened, snapshot: RobotSnapshot): Unit =
      snapshot.batteryVoltage.foreach { volts =>
        readings = (readings :+ volts).takeRight(settings.batteryReadings)
        val sustained = readings.size == settings.batteryReadings
        if (safety.isEmpty && sustained && readings.forall(_ < settings.lowBattery)) {
          val reason = RobotGuard.batteryLow(readings.max, readings.size, settings)
          context.log.warn("Robot [{}]: {}; stopping and sitting down", robotId, reason)
          safety = Some(reason)
          report()
          leases.values.toSet.foreach((holder: AppInfo) => holder.events ! AppEvent.SafetyStop(robotId, reason))
          stopWalking(c, reason, thenSit = true)
        } else if (safety.isDefined && sustained && readings.forall(_ > settings.batteryOk)) {
          context.log.info("Robot [{}]: battery back at {} V; motion allowed again", robotId, volts)
          safety = None
          report()
          leases.values.toSet.foreach((holder: AppInfo) => holder.events ! AppEvent.SafetyCleared(robotId))
        }
      }

    private def stopWalking(c: RobotAccess.Opened, why: String, thenSit: Boolean = false): Unit = {
      if (walking.isDefined || thenSit) context.log.info("Robot [{}]: stop ({})", robotId, why)
      timers.cancel(WalkKey)
      walking = None
      safetyCall(c, if (thenSit) SafetyStep.StopThenSit else SafetyStep.StopOnly, RpcMethod.Stop.call(),
        settings.callTimeout)
    }

    private def walkCall(w: Operation.Walk): RpcCall =
      RpcMethod.Walk.call(RpcValue.Number(w.vx.toFloat), RpcValue.Number(w.vy.toFloat),
        RpcValue.Number(w.omega.toFloat))

    private def reply(replyTo: ActorRef[CallResult], operation: Operation,
        result: Either[RobotFailure, Option[RpcValue]]): Unit =
      replyTo ! CallResult(robotId, operation.name, result)

    // `once`: a send is sent once (no retries), as the seed's no-response sender does. A walk's or a posture's answer
    // comes back here, so the guard's own bookkeeping (walk refresh, stop after a failed posture) is the same for both
    // doors. Every other operation leaves nothing to keep: the robot's command owner answers its caller directly,
    // which spares each call the hop back through this actor (and the thread it may wake).
    private def call(c: RobotAccess.Opened, rpc: RpcCall, operation: Operation, replyTo: ActorRef[CallResult],
        once: Boolean, priority: Priority = Priority.Command, timeout: FiniteDuration = settings.callTimeout): Unit = {
      val idempotent = if (once) Some(false) else None
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

    private def run(c: RobotAccess.Opened, app: AppInfo, operation: Operation,
        replyTo: ActorRef[CallResult], once: Boolean): Unit = operation match {
      case w: Operation.Walk =>
        // The first walk is confirmed by the robot; afterwards the middleware keeps it fresh inside the robot's lease.
        // Until then nothing is refreshed: neither this walk, unconfirmed, nor the one it replaces.
        walking = Some(w -> app)
        timers.cancel(WalkKey)
        call(c, walkCall(w), operation, replyTo, once)
      case Operation.Stop() =>
        timers.cancel(WalkKey)
        walking = None
        call(c, RpcMethod.Stop.call(), operation, replyTo, once, Priority.Safety)
      case Operation.Head(pan, tilt) =>
        val rpc = RpcMethod.Head.call(RpcValue.Number(pan.toFloat), RpcValue.Number(tilt.toFloat))
        call(c, rpc, operation, replyTo, once)
      case Operation.Arms(ls, le, rs, re) =>
        val rpc = RpcMethod.Arms.call(Vector(ls, le, rs, re).map(v => RpcValue.Number(v.toFloat)): _*)
        call(c, rpc, operation, replyTo, once)
      case Operation.Posture(p) =>
        timers.cancel(WalkKey)
        walking = None
        val rpc = RpcMethod.Posture.call(RpcValue.Text(p.name))
        call(c, rpc, operation, replyTo, once, timeout = settings.postureTimeout)
      case Operation.Say(text) => call(c, RpcMethod.Say.call(RpcValue.Text(text)), operation, replyTo, once)
      case r: Operation.RawCall =>
        val timeout = if (RpcMethod.find(r.module, r.method).contains(RpcMethod.Posture)) settings.postureTimeout
        else settings.callTimeout
        call(c, RpcCall(r.module, r.method, r.params), operation, replyTo, once, timeout = timeout)
    }
  }
}
