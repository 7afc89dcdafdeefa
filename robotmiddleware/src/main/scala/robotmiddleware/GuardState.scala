package robotmiddleware

import akka.actor.typed.ActorRef

import naogateway.wire.{ActuatorGroup, Posture, RpcMethod, RpcValue}
import naogateway.api.{LinkStats, RobotEvent, RobotFailure, RobotOffline, RobotOnline, VisionFrame}

/** Everything a robot's guard knows, as one immutable value: the lease holders, the walk it keeps alive, the safety
  * hold and the battery readings behind it, whether the robot is online, the one safety stop in flight, and the apps'
  * watchers. Each change is a named transition that returns what the guard is to do; `RobotGuard` only carries them
  * out, so every decision here is tested without actors (GuardStateSpec).
  */
private[robotmiddleware] final case class GuardState(
    leases: Map[ActuatorGroup, AppInfo] = Map.empty,
    walking: Option[(Operation.Walk, AppInfo)] = None,
    safety: Option[String] = None,
    online: Boolean = false,
    reconnectedWhileConnecting: Boolean = false,
    stopInFlight: Boolean = false,
    sitAfterStop: Boolean = false,
    readings: Vector[Double] = Vector.empty,
    statsWatchers: Set[ActorRef[LinkStats]] = Set.empty,
    visionWatchers: Map[ActorRef[VisionFrame], Boolean] = Map.empty
) {
  import GuardState._

  /** The lease holders and the safety hold, as the middleware's table shows them. */
  def holds(robotId: Int): RobotHolds = RobotHolds(robotId, leases.map { case (g, app) => g -> app.name }, safety)

  /** Why `app`'s `operation` may not run now (an argument out of range, offline, lease, safety), the same for both
    * doors; None when it may.
    */
  def refusal(robotId: Int, app: AppInfo, operation: Operation, limits: ArgumentLimits): Option[RobotFailure] = {
    val group = operation.group
    val held = group.forall(g => leases.get(g).exists(_.events == app.events))
    val outOfRange = limits.check(operation)
    if (outOfRange.isDefined) Some(RobotFailure.RobotError(robotId, outOfRange.get))
    else if (!online) Some(RobotFailure.RobotOffline(robotId))
    else if (!held) Some(RobotFailure.LeaseNotHeld(robotId, group.get, group.flatMap(leases.get).map(_.name)))
    else if (safety.isDefined && refusedWhenUnsafe(operation)) Some(RobotFailure.SafetyHold(robotId, safety.get))
    else None
  }

  /** The robot actor's snapshot said whether the robot is online (any event before it is older). */
  def snapshotReceived(isOnline: Boolean): GuardState = copy(online = isOnline)

  /** An event of the robot, in any state: offline forgets the walk, so it is not resumed by surprise (the robot's own
    * walk lease stops it).
    */
  def eventReceived(event: RobotEvent): GuardState = event match {
    case RobotOnline(_, _)  => copy(online = true)
    case RobotOffline(_, _) => copy(online = false, walking = None)
    case _                  => this
  }

  /** An event while the guard connects to the robot's children: a robot that came back (seen offline before) gets its
    * reconnect stop once the guard is ready; one that went offline again gets it from its next online event instead.
    */
  def eventWhileConnecting(event: RobotEvent): GuardState = {
    val next = eventReceived(event)
    event match {
      case RobotOnline(_, _) if !online => next.copy(reconnectedWhileConnecting = true)
      case RobotOffline(_, _)           => next.copy(reconnectedWhileConnecting = false)
      case _                            => next
    }
  }

  /** An event while ready; true when the robot has come back (seen offline before), to be stopped: a stale online event
    * must not supersede an app's motion.
    */
  def eventWhileReady(event: RobotEvent): (GuardState, Boolean) =
    (eventReceived(event), event.isInstanceOf[RobotOnline] && !online)

  /** The reconnect stop goes out now (no longer owed). */
  def reconnectStopped: GuardState = copy(reconnectedWhileConnecting = false)

  /** `app` asks for `groups` at its priority: all or none. Refused with the first group (in the docs' group order) held
    * by another app at equal or higher priority; granted with the groups taken from other holders, in that order.
    */
  def acquire(app: AppInfo,
      groups: Set[ActuatorGroup]): Either[(ActuatorGroup, AppInfo), (GuardState, Vector[(ActuatorGroup, AppInfo)])] = {
    val wanted = ActuatorGroup.all.filter(groups)
    val conflict = wanted.flatMap { group =>
      leases.get(group).filter(holder => holder.events != app.events && holder.priority >= app.priority).map(group -> _)
    }.headOption
    conflict.toLeft {
      val preempted = wanted.flatMap(g => leases.get(g).filter(_.events != app.events).map(g -> _)).toVector
      (copy(leases = leases ++ wanted.map(_ -> app)), preempted)
    }
  }

  /** `app` gives `group` back; None when it did not hold it. */
  def release(app: ActorRef[AppEvent], group: ActuatorGroup): Option[GuardState] =
    if (leases.get(group).exists(_.events == app)) Some(copy(leases = leases - group)) else None

  /** `app`'s system is gone: its leases are free; with the groups it held. */
  def appGone(app: ActorRef[AppEvent]): (GuardState, Set[ActuatorGroup]) = {
    val held = leases.collect { case (g, holder) if holder.events == app => g }.toSet
    (copy(leases = leases -- held), held)
  }

  /** An app's walk goes to the robot: kept alive only once the robot has confirmed it (`walkAnswered`). */
  def walkStarted(walk: Operation.Walk, app: AppInfo): GuardState = copy(walking = Some(walk -> app))

  /** No walk is kept alive any more (a stop, a posture, the walk lease gone, the children restarted). */
  def walkEnded: GuardState = copy(walking = None)

  /** The robot answered `walk`: None when it is not the walk kept alive; else whether it is now refreshed (confirmed)
    * or forgotten (refused: never sent again).
    */
  def walkAnswered(walk: Operation.Walk, confirmed: Boolean): Option[(GuardState, Boolean)] =
    if (!walking.exists(_._1 == walk)) None
    else if (confirmed) Some((this, true))
    else Some((walkEnded, false))

  /** The guard wants `step` sent; true when it goes now. One safety stop is in flight at a time (the response actor
    * resends it when it is lost), so events anyone can provoke cannot become a flood of stops; a hold that wants the
    * robot sitting while a stop is in flight sits once that stop is answered.
    */
  def safetyStep(step: SafetyStep): (GuardState, Boolean) =
    if (step.stops && stopInFlight) (if (step == SafetyStep.StopThenSit) copy(sitAfterStop = true) else this, false)
    else (if (step.stops) copy(stopInFlight = true) else this, true)

  /** `step` was answered (or failed); true when the robot is to sit now: the step or a hold wanted it sitting, and the
    * hold is still on.
    */
  def safetyStepDone(step: SafetyStep): (GuardState, Boolean) = {
    val wantsSit = step == SafetyStep.StopThenSit || (step.stops && sitAfterStop)
    val next = if (step.stops) copy(stopInFlight = false, sitAfterStop = false) else this
    (next, wantsSit && safety.isDefined)
  }

  /** A battery reading of `volts`: the hold starts on `batteryReadings` readings in a row below `lowBattery`, and ends
    * on as many above `batteryOk`; with the change, if any.
    */
  def batteryRead(volts: Double, settings: MiddlewareSettings): (GuardState, Option[BatteryChange]) = {
    val kept = (readings :+ volts).takeRight(settings.batteryReadings)
    val next = copy(readings = kept)
    val sustained = kept.size == settings.batteryReadings
    if (safety.isEmpty && sustained && kept.forall(_ < settings.lowBattery)) {
      val reason = GuardState.batteryLow(kept.max, kept.size, settings)
      (next.copy(safety = Some(reason)), Some(BatteryChange.HoldStarted(reason)))
    } else if (safety.isDefined && sustained && kept.forall(_ > settings.batteryOk))
      (next.copy(safety = None), Some(BatteryChange.HoldCleared))
    else (next, None)
  }

  /** An app watches the camera (or changes whether it wants grids); true when it is new (to be watched). */
  def visionWatched(subscriber: ActorRef[VisionFrame], grid: Boolean): (GuardState, Boolean) =
    (copy(visionWatchers = visionWatchers.updated(subscriber, grid)), !visionWatchers.contains(subscriber))

  /** A camera watcher stopped. */
  def visionGone(subscriber: ActorRef[VisionFrame]): GuardState = copy(visionWatchers = visionWatchers - subscriber)

  /** An app watches the link figures. */
  def statsWatched(subscriber: ActorRef[LinkStats]): GuardState = copy(statsWatchers = statsWatchers + subscriber)

  /** A link-figures watcher stopped. */
  def statsGone(subscriber: ActorRef[LinkStats]): GuardState = copy(statsWatchers = statsWatchers - subscriber)
}

/** The guard's rules that need no state. */
private[robotmiddleware] object GuardState {

  /** The guard's own calls that keep a robot safe; each one's answer comes back with its own step. */
  sealed abstract class SafetyStep(val describe: String, val stops: Boolean) extends Product with Serializable

  /** The steps. */
  object SafetyStep {

    /** The stop of a safety hold, followed by a sit once the robot has stopped. */
    case object StopThenSit extends SafetyStep("stop", stops = true)

    /** A stop that ends a walk (lease released or taken, app gone, a motion failed). */
    case object StopOnly extends SafetyStep("stop only", stops = true)

    /** The stop a robot gets when it comes back online. */
    case object StopAfterReconnect extends SafetyStep("stop after reconnect", stops = true)

    /** The sit of a safety hold. */
    case object Sit extends SafetyStep("sit", stops = false)
  }

  /** How a battery reading changed the safety hold. */
  sealed trait BatteryChange extends Product with Serializable

  /** The two changes. */
  object BatteryChange {

    /** The hold starts, for `reason`: apps are told, the robot stops and sits. */
    final case class HoldStarted(reason: String) extends BatteryChange

    /** The hold ends: motion is allowed again. */
    case object HoldCleared extends BatteryChange
  }

  /** The reason of a battery hold, with how it ends: what `SafetyStop`, `SafetyHold` and `robotctl doctor` say. */
  def batteryLow(volts: Double, readings: Int, settings: MiddlewareSettings): String =
    f"battery low: $volts%.2f V or less for $readings keep-alives (below ${settings.lowBattery}%.2f V); it clears " +
      f"by itself once $readings keep-alives in a row read above ${settings.batteryOk}%.2f V: swap or charge the " +
      "battery (a simulated robot recharges while it sits; `robotctl battery <id> swap` swaps its battery at once)"

  /** Whether `operation` is refused while a safety hold is on: anything that moves, but a stop or a sit. */
  def refusedWhenUnsafe(operation: Operation): Boolean = operation match {
    case _: Operation.Walk | _: Operation.Arms => true
    case Operation.Posture(p)                  => p != Posture.Sit
    case r: Operation.RawCall =>
      (r.group.contains(ActuatorGroup.Walk) && !RpcMethod.find(r.module, r.method).contains(RpcMethod.Stop) &&
        !(RpcMethod.find(r.module, r.method).contains(RpcMethod.Posture) && r.params == Vector(
          RpcValue.Text(Posture.Sit.name)))) ||
      r.group.contains(ActuatorGroup.Arms)
    case _ => false
  }
}
