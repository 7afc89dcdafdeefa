package robotmiddleware

import naogateway.api.RobotFailure

import naogateway.wire.ActuatorGroup

import scala.concurrent.duration._
import scala.concurrent.{ExecutionContext, Future}

import akka.actor.typed.receptionist.Receptionist
import akka.actor.typed.scaladsl.AskPattern._
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, ActorSystem, Behavior, Terminated}
import akka.stream.OverflowStrategy
import akka.stream.scaladsl.Source
import akka.stream.typed.scaladsl.ActorSource
import akka.util.Timeout
import akka.{Done, NotUsed}

import naogateway.api.{CallResult, LinkStats, RobotEvent, RobotSnapshot, ServoReadings, VisionFrame}
import naogateway.wire.{Posture, RpcValue}
import naogateway.wire.gamecontroller.{GameControlData, PlayerPenalty}

/** What apps program against: commands as futures, robot data as streams; no app ever sees a gateway actor.
  *
  * Two doors to a robot (docs/writing-apps.md): a call (`walk` … `call`) completes with the robot's answer; a send
  * (`send`) completes once the middleware has accepted it and drops the robot's answer. Both go through the same checks
  * (lease, online, safety) and one ordered path, so a send followed by a call reaches the robot in that order. Every
  * future fails only with a `RobotFailure`; no method throws.
  */
trait RobotInterface {

  /** This app's name, as other apps and logs see it. */
  def appName: String

  /** Every known robot's latest snapshot. */
  def robots(): Future[Vector[RobotSnapshot]]

  /** Takes the leases of `groups` on a robot as one: all of them, or, failing with `LeaseNotHeld` when a holder of
    * equal or higher priority has any of them, none.
    */
  def acquire(robotId: Int, groups: ActuatorGroup*): Future[Done]

  /** Gives leases back (releasing `walk` stops the robot). */
  def release(robotId: Int, groups: ActuatorGroup*): Unit

  /** Walks with these velocities (m/s, m/s, rad/s) until changed or stopped; needs the `walk` lease. */
  def walk(robotId: Int, vx: Double, vy: Double, omega: Double): Future[Done]

  /** Stops walking; needs the `walk` lease. */
  def stop(robotId: Int): Future[Done]

  /** Turns the head (radians); needs the `head` lease. */
  def head(robotId: Int, pan: Double, tilt: Double): Future[Done]

  /** Sets the arm joints (radians); needs the `arms` lease. */
  def arms(
      robotId: Int, leftShoulder: Double, leftElbow: Double, rightShoulder: Double, rightElbow: Double): Future[Done]

  /** Goes to a posture; completes with the posture reached when the motion has ended (normally `target`, `Fallen` if
    * the robot fell on the way); needs `walk`.
    */
  def posture(robotId: Int, target: Posture.Target): Future[Posture]

  /** Says a text; needs the `speech` lease. */
  def say(robotId: Int, text: String): Future[Done]

  /** Any call of the robot's RPC interface (motion and speech calls need their lease). */
  def call(robotId: Int, module: String, method: String, params: RpcValue*): Future[Option[RpcValue]]

  /** Sends any call of the robot's RPC interface without waiting for the robot: completes with `Done` once the
    * middleware accepted it (fails with the same `RobotFailure` a call would for a lease, an offline robot or a safety
    * hold); the robot's answer, or its error, is dropped. Ordered with this app's calls and sends, sent once.
    */
  final def send(robotId: Int, module: String, method: String, params: RpcValue*): Future[Done] =
    send(robotId, Operation.RawCall(module, method, params.toVector))

  /** Sends a typed operation (`Operation.Walk`, `Operation.Head`, …) the same way: accepted, its answer dropped. */
  def send(robotId: Int, operation: Operation): Future[Done]

  /** The robot's keep-alive snapshots, starting with the latest known. */
  def status(robotId: Int): Source[RobotSnapshot, NotUsed]

  /** Snapshots of every robot. */
  def allStatus: Source[RobotSnapshot, NotUsed]

  /** A robot's servo telemetry (docs/protocol.md 6.8), read from [[status]]: the latest known at once, then each new
    * one as it arrives (about once a second), once each. `ServoLimits` (`MiddlewareSettings.servoLimits`) says which
    * servos are hot or low on voltage. The telemetry is dropped, not emitted empty, when the robot goes offline or
    * restarts; the next one comes with its next telemetry.
    */
  def servos(robotId: Int): Source[ServoReadings, NotUsed] =
    status(robotId).map(_.servos).statefulMapConcat { () =>
      var last: Option[ServoReadings] = None
      now =>
        if (now.isEmpty || now == last) { last = now; Nil }
        else { last = now; now.toList }
    }

  /** HaViMo2 frames of a robot, newest only; `grid` adds the (large) grid frames. */
  def vision(robotId: Int, grid: Boolean = false): Source[VisionFrame, NotUsed]

  /** A robot's link figures: the current ones at once, then about once a second. */
  def linkStats(robotId: Int): Source[LinkStats, NotUsed]

  /** GameController packets as they arrive. */
  def gameState: Source[GameControlData, NotUsed]

  /** The GameController's penalty of player `player` of team `teamNumber`, read from [[gameState]]: `None` while the
    * player plays, the penalty (by name, with the seconds left) while it is off the game; each change once, not each
    * packet. A robot is the player numbered by its robot id in the team its keep-alive names (docs/protocol.md 10.11).
    */
  def penalty(teamNumber: Int, player: Int): Source[Option[PlayerPenalty], NotUsed] =
    gameState.map(_.penaltyOf(teamNumber, player)).statefulMapConcat { () =>
      var last: Option[Option[PlayerPenalty]] = None
      now => if (last.contains(now)) Nil else { last = Some(now); List(now) }
    }

  /** Robots going online, offline, restarting, changing link quality. */
  def robotEvents: Source[RobotEvent, NotUsed]

  /** What the middleware tells this app: preempted leases, safety stops. */
  def appEvents: Source[AppEvent, NotUsed]

  /** Every robot's lease holders and safety hold, as the middleware's guards last reported them (robots no app has used
    * yet are not listed). Answered on the gateway's node only: the message does not cross nodes.
    */
  def holds(): Future[Vector[RobotHolds]]

  /** Ends this app's session: its leases are released and its walking robots stopped. */
  def close(): Unit
}

/** Connecting an app to the middleware, in the app's own actor system. */
object RobotClient {

  /** Finds the middleware through the receptionist (local, or cluster-wide when the system is a cluster node). */
  def find(system: ActorSystem[_], within: FiniteDuration = 10.seconds): Future[ActorRef[RobotMiddleware.Command]] = {
    implicit val ec: ExecutionContext = system.executionContext
    val deadline = within.fromNow
    val retry = MiddlewareSettings(system).clientFindRetry
    def attempt(): Future[ActorRef[RobotMiddleware.Command]] =
      system.receptionist.ask[Receptionist.Listing](Receptionist.Find(RobotMiddleware.ServiceKey, _))(Timeout(within),
        system.scheduler)
        .flatMap { listing =>
          listing.serviceInstances(RobotMiddleware.ServiceKey).headOption match {
            case Some(ref) => Future.successful(ref)
            case None if deadline.hasTimeLeft() =>
              akka.pattern.after(retry)(attempt())(system)
            case None => Future.failed(new NoSuchElementException(s"no robot middleware found within $within"))
          }
        }
    attempt()
  }

  /** Registers an app called `appName` with `priority` (higher preempts lower) and returns its interface. Fails only
    * with a `RobotFailure` (robot id 0, operation "connect"): `Timeout` when the middleware does not answer within
    * `timeout`; then the session made for it is closed again.
    */
  def connect(system: ActorSystem[_], middleware: ActorRef[RobotMiddleware.Command], appName: String, priority: Int = 0,
      timeout: FiniteDuration = 10.seconds): Future[RobotInterface] =
    asRobotFailure(0, "connect", timeout) {
      implicit val s: ActorSystem[_] = system
      implicit val t: Timeout = Timeout(timeout)
      val name = s"app-${java.net.URLEncoder.encode(appName, "UTF-8")}-${System.nanoTime()}"
      val session = system.systemActorOf(AppSessionActor(), name)
      val registered =
        middleware.ask[RobotMiddleware.AppRegistered](RobotMiddleware.RegisterApp(appName, priority, session, _))
      registered.failed.foreach(_ => session ! SessionMessage.Close)(ExecutionContext.parasitic)
      registered.map(_ => new ClientImpl(system, middleware, session, appName, timeout): RobotInterface)(
        ExecutionContext.parasitic)
    }

  /** `f`, failing only with a `RobotFailure`: a timeout as `Timeout` after `waited`, anything else (a throw while
    * starting `f`, a dead system, a message that could not be serialized) as `Overloaded` naming the cause.
    */
  private[robotmiddleware] def asRobotFailure[R](robotId: Int, operation: String, waited: FiniteDuration)(
      f: => Future[R]): Future[R] = {
    val started =
      try f
      catch { case scala.util.control.NonFatal(e) => Future.failed(e) }
    started.transform {
      case ok @ scala.util.Success(_)                   => ok
      case failed @ scala.util.Failure(_: RobotFailure) => failed
      case scala.util.Failure(_: java.util.concurrent.TimeoutException) =>
        scala.util.Failure(RobotFailure.Timeout(robotId, operation, waited.toMillis))
      case scala.util.Failure(e) =>
        val cause = s"${e.getClass.getSimpleName}: ${e.getMessage}"
        scala.util.Failure(RobotFailure.Overloaded(robotId, s"$operation could not reach the middleware: $cause"))
    }(scala.concurrent.ExecutionContext.parasitic)
  }

  /** `find` then `connect`. */
  def apply(system: ActorSystem[_], appName: String, priority: Int = 0): Future[RobotInterface] =
    find(system).flatMap(connect(system, _, appName, priority))(system.executionContext)

  private final class ClientImpl(
      system: ActorSystem[_],
      middleware: ActorRef[RobotMiddleware.Command],
      session: ActorRef[SessionMessage],
      val appName: String,
      timeout: FiniteDuration
  ) extends RobotInterface {
    private implicit val s: ActorSystem[_] = system
    // Posture changes take seconds on the robot; the ask outlives the middleware's own timeouts (client.ask-margin).
    private implicit val askTimeout: Timeout = Timeout(timeout + MiddlewareSettings(system).clientAskMargin)
    // The futures are composed with short, non-blocking steps on the thread that completes them: no hop to a
    // dispatcher per step (a call's answer reaches the app sooner), and they still complete when the system is gone.
    private implicit val ec: ExecutionContext = ExecutionContext.parasitic

    /** An ask of the middleware that fails only with a `RobotFailure`: a lost answer (Akka's `AskTimeoutException`) as
      * `Timeout`; an ask that cannot even start (the app's actor system is shutting down) or any other error as
      * `Overloaded` with the cause in words; never a synchronous throw.
      */
    private def ask[R](robotId: Int, operation: String)(message: ActorRef[R] => RobotMiddleware.Command): Future[R] =
      RobotClient.asRobotFailure(robotId, operation, askTimeout.duration)(middleware.ask[R](message))

    private def execute(robotId: Int, operation: Operation): Future[Option[RpcValue]] =
      ask[CallResult](robotId, operation.name)(RobotMiddleware.Execute(session, robotId, operation, _)).flatMap { r =>
        r.result.fold(error => Future.failed(AppFailure(robotId, error)), Future.successful)
      }

    private def done(f: Future[Option[RpcValue]]): Future[Done] = f.map(_ => Done)

    // Robot id 0: the list concerns no single robot.
    def robots(): Future[Vector[RobotSnapshot]] =
      ask[RobotMiddleware.RobotList](0, "robots")(RobotMiddleware.ListRobots(_)).map(_.robots)

    // One request for the whole set, so the middleware grants all of it or nothing; no groups is nothing to ask.
    def acquire(robotId: Int, groups: ActuatorGroup*): Future[Done] =
      if (groups.isEmpty) Future.successful(Done)
      else {
        val set = groups.toSet
        ask[RobotMiddleware.LeaseResult](robotId,
          s"acquire ${ActuatorGroup.all.filter(set).map(_.name).mkString(",")}")(
          RobotMiddleware.Acquire(session, robotId, set, _)
        ).flatMap(r => r.result.fold(Future.failed, _ => Future.successful(Done)))
      }

    def release(robotId: Int, groups: ActuatorGroup*): Unit =
      groups.foreach(g => middleware ! RobotMiddleware.Release(session, robotId, g))

    // Velocities that are no numbers fail the future like any refusal, never the caller's thread; finite ones out of
    // range are the guard's to refuse, which knows the limits.
    def walk(robotId: Int, vx: Double, vy: Double, omega: Double): Future[Done] =
      Seq("vx" -> vx, "vy" -> vy, "omega" -> omega).find { case (_, v) => v.isNaN || v.isInfinite } match {
        case None => done(execute(robotId, Operation.Walk(vx, vy, omega)))
        case Some((name, v)) =>
          Future.failed(RobotFailure.RobotError(robotId,
              s"${ArgumentLimits.Prefix}$name ${ArgumentLimits.show(v)}, allowed finite numbers"))
      }
    def stop(robotId: Int): Future[Done] = done(execute(robotId, Operation.Stop()))
    def head(robotId: Int, pan: Double, tilt: Double): Future[Done] = done(execute(robotId, Operation.Head(pan, tilt)))
    def arms(robotId: Int, ls: Double, le: Double, rs: Double, re: Double): Future[Done] =
      done(execute(robotId, Operation.Arms(ls, le, rs, re)))
    def posture(robotId: Int, target: Posture.Target): Future[Posture] =
      execute(robotId, Operation.Posture(target)).flatMap {
        case Some(RpcValue.Text(reached)) => Future.successful(Posture.reported(reached))
        case None                         => Future.successful(target)
        case Some(other) =>
          Future.failed(RobotFailure.RobotError(robotId, s"motion.posture answered $other, not a posture name"))
      }
    def say(robotId: Int, text: String): Future[Done] = done(execute(robotId, Operation.Say(text)))
    def call(robotId: Int, module: String, method: String, params: RpcValue*): Future[Option[RpcValue]] =
      execute(robotId, Operation.RawCall(module, method, params.toVector))

    def send(robotId: Int, operation: Operation): Future[Done] =
      ask[RobotMiddleware.SendResult](robotId, operation.name)(RobotMiddleware.Send(session, robotId, operation, _))
        .flatMap(r => r.result.fold(Future.failed, _ => Future.successful(Done)))

    private def source[T](buffer: Int)(register: ActorRef[T] => Unit): Source[T, NotUsed] =
      ActorSource
        .actorRef[T](PartialFunction.empty, PartialFunction.empty, buffer, OverflowStrategy.dropHead)
        .mapMaterializedValue { ref => register(ref); NotUsed }

    def status(robotId: Int): Source[RobotSnapshot, NotUsed] =
      source[RobotSnapshot](16)(ref => middleware ! RobotMiddleware.WatchStatus(Some(robotId), ref))
    def allStatus: Source[RobotSnapshot, NotUsed] =
      source[RobotSnapshot](256)(ref => middleware ! RobotMiddleware.WatchStatus(None, ref))
    def vision(robotId: Int, grid: Boolean): Source[VisionFrame, NotUsed] =
      source[VisionFrame](1)(ref => middleware ! RobotMiddleware.WatchVision(robotId, ref, grid))
    def linkStats(robotId: Int): Source[LinkStats, NotUsed] =
      source[LinkStats](4)(ref => middleware ! RobotMiddleware.WatchLinkStats(robotId, ref))
    def gameState: Source[GameControlData, NotUsed] =
      source[GameControlData](4)(ref => middleware ! RobotMiddleware.WatchGame(ref))
    def robotEvents: Source[RobotEvent, NotUsed] =
      source[RobotEvent](64)(ref => middleware ! RobotMiddleware.WatchEvents(ref))
    def appEvents: Source[AppEvent, NotUsed] =
      source[AppEvent](64)(ref => session ! SessionMessage.SubscribeAppEvents(ref))

    def holds(): Future[Vector[RobotHolds]] =
      ask[Vector[RobotHolds]](0, "holds")(RobotMiddleware.getHolds(_))

    def close(): Unit = session ! SessionMessage.Close
  }
}

/** An app's session: its identity at the middleware, and the fan-out of the middleware's events to local streams. */
object AppSessionActor {

  /** A session with no subscribers yet. */
  def apply(): Behavior[SessionMessage] = running(Set.empty)

  private def running(subscribers: Set[ActorRef[AppEvent]]): Behavior[SessionMessage] =
    Behaviors
      .receive[SessionMessage] {
        case (context, SessionMessage.SubscribeAppEvents(subscriber)) =>
          context.watch(subscriber)
          running(subscribers + subscriber)
        case (_, SessionMessage.Close) => Behaviors.stopped
        case (_, event: AppEvent) =>
          subscribers.foreach(_ ! event)
          Behaviors.same
      }
      .receiveSignal { case (_, Terminated(ref)) =>
        running(subscribers.filterNot(_ == ref))
      }
}
