package robotmiddleware

import naogateway.wire.ActuatorGroup

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit, TestProbe}
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, Behavior}
import org.scalatest.LoneElement
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.{GatewayAccess, RobotAccess}
import naogateway.api.{
  CallResult,
  GatewayEvent,
  LinkQuality,
  LinkStats,
  Priority,
  RobotEvent,
  RobotFailure,
  RobotOffline,
  RobotOnline,
  RobotSnapshot,
  RobotStatusUpdated
}
import naogateway.wire.{Posture, RpcCall, RpcValue}

class RobotMiddlewareSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing with LoneElement {
  private val settings = MiddlewareSettings(10.8, 11.0, 200.millis, 2.seconds, 5.seconds, 1.second, 16)
  private val robotAddress = new InetSocketAddress("127.0.0.1", 3838)

  /** A gateway that knows robot 1 and hands out probes as the robot's children. With `holdConnect` the robot does not
    * answer a guard's `Open` by itself: the test finds the guard's reply ref in `connects` and answers when it wants.
    * The robot answers `GetSnapshot` with the online state `snapshotOnline` (online unless a test says otherwise); with
    * `None` it does not answer.
    */
  private final class Fixture(holdConnect: Boolean = false, snapshotOnline: Option[Boolean] = Some(true),
      middlewareSettings: MiddlewareSettings = settings, known: Vector[RobotSnapshot] = Vector.empty) {
    val response: TestProbe[RobotAccess.Call] = createTestProbe[RobotAccess.Call]()
    val vision: TestProbe[RobotAccess.RegisterVision] = createTestProbe[RobotAccess.RegisterVision]()
    val events: TestProbe[ActorRef[GatewayEvent]] = createTestProbe[ActorRef[GatewayEvent]]()
    val connects: TestProbe[ActorRef[RobotAccess.Opened]] = createTestProbe[ActorRef[RobotAccess.Opened]]()

    /** Every `Open` the robot got, held or answered. */
    val connectsSeen: TestProbe[ActorRef[RobotAccess.Opened]] = createTestProbe[ActorRef[RobotAccess.Opened]]()
    // All the middleware gets of the robot's children: no sender, stream or heartbeat to send to.
    val connected: RobotAccess.Opened = RobotAccess.Opened(1, response.ref, vision.ref)

    /** What the robot answers an `Open` with: a test swaps it for new children to stand in for a restart. */
    @volatile var current: RobotAccess.Opened = connected

    // The robot actor as the middleware sees it: only what RobotAccess.Command lets it send.
    private val robot: Behavior[RobotAccess.Command] = Behaviors.receiveMessage {
      case RobotAccess.Open(replyTo) =>
        connectsSeen.ref ! replyTo
        if (holdConnect) connects.ref ! replyTo else replyTo ! current
        Behaviors.same
      case RobotAccess.GetSnapshot(replyTo) =>
        snapshotOnline.foreach(online => replyTo ! RobotSnapshot(1, robotAddress, online = online))
        Behaviors.same
      case RobotAccess.GetLinkStats(replyTo) =>
        replyTo ! linkStats
        Behaviors.same
    }
    private val robotRef = spawn(robot)
    private val gateway: Behavior[GatewayAccess.Command] = Behaviors.receiveMessage {
      case GatewayAccess.Subscribe(subscriber) =>
        events.ref ! subscriber
        Behaviors.same
      case GatewayAccess.GetRobotAccess(id, replyTo) =>
        replyTo ! (if (id == 1) Some(robotRef) else None)
        Behaviors.same
      case GatewayAccess.GetRobots(replyTo) =>
        replyTo ! known
        Behaviors.same
      case _ => Behaviors.same
    }
    val middleware: ActorRef[RobotMiddleware.Command] = spawn(RobotMiddleware(spawn(gateway), middlewareSettings))
    val publish: ActorRef[GatewayEvent] = events.receiveMessage()
    publish ! RobotOnline(1, robotAddress)

    def app(name: String, priority: Int): (ActorRef[SessionMessage], TestProbe[AppEvent]) = {
      val appEvents = createTestProbe[AppEvent]()
      val session = spawn(AppSessionActor())
      session ! SessionMessage.SubscribeAppEvents(appEvents.ref)
      val registered = createTestProbe[RobotMiddleware.AppRegistered]()
      middleware ! RobotMiddleware.RegisterApp(name, priority, session, registered.ref)
      registered.expectMessage(RobotMiddleware.AppRegistered(name))
      (session, appEvents)
    }

    def acquire(session: ActorRef[SessionMessage], group: ActuatorGroup): RobotMiddleware.LeaseResult = {
      val result = createTestProbe[RobotMiddleware.LeaseResult]()
      middleware ! RobotMiddleware.Acquire(session, 1, group, result.ref)
      result.receiveMessage()
    }

    def acquireAll(session: ActorRef[SessionMessage], groups: ActuatorGroup*): RobotMiddleware.LeaseResult = {
      val result = createTestProbe[RobotMiddleware.LeaseResult]()
      middleware ! RobotMiddleware.Acquire(session, 1, groups.toSet, result.ref)
      result.receiveMessage()
    }

    def execute(session: ActorRef[SessionMessage], operation: Operation): TestProbe[CallResult] = {
      val result = createTestProbe[CallResult]()
      middleware ! RobotMiddleware.Execute(session, 1, operation, result.ref)
      result
    }

    /** The middleware's lease holders and safety holds. */
    def holds(): Vector[RobotHolds] = {
      val answer = createTestProbe[Vector[RobotHolds]]()
      middleware ! RobotMiddleware.getHolds(answer.ref)
      answer.receiveMessage()
    }

    def expectCall(name: String): RobotAccess.Call = {
      val call = response.fishForMessage(3.seconds) {
        case c: RobotAccess.Call if c.call.name == name => akka.actor.testkit.typed.FishingOutcome.Complete
        case _                                          => akka.actor.testkit.typed.FishingOutcome.ContinueAndIgnore
      }
      call.last.asInstanceOf[RobotAccess.Call]
    }
  }

  private val linkStats = LinkStats(1, 10, 9, 400, 300, Some(2.5), 0.1, 0, Map.empty)

  "The middleware" must {
    "reach the robot's new children after they were restarted, instead of calling dead refs" in {
      val f = new Fixture
      val (app, _) = f.app("teleop", 1)
      f.acquire(app, ActuatorGroup.Head).result shouldBe Right(())
      f.execute(app, Operation.Head(0.1, 0.0))
      f.expectCall("motion.head").replyTo ! CallResult(1, "motion.head", Right(None))
      val fresh = createTestProbe[RobotAccess.Call]()
      f.current = f.connected.copy(response = fresh.ref)
      f.connectsSeen.receiveMessage() // the guard's first connect
      f.response.stop()
      // The guard watches the refs it holds: their end makes it connect again, and calls wait meanwhile.
      f.connectsSeen.receiveMessage()
      val result = f.execute(app, Operation.Head(0.2, 0.0))
      val call = fresh.fishForMessage(3.seconds) {
        case c: RobotAccess.Call if c.call.name == "motion.head" => akka.actor.testkit.typed.FishingOutcome.Complete
        case _ => akka.actor.testkit.typed.FishingOutcome.ContinueAndIgnore
      }.last.asInstanceOf[RobotAccess.Call]
      call.replyTo ! CallResult(1, "motion.head", Right(None))
      result.receiveMessage().result shouldBe Right(None)
    }
    "sit a robot with a low battery after its one stop in flight, sending no second stop meanwhile" in {
      val f = new Fixture
      val (app, events) = f.app("walker", 1)
      f.acquire(app, ActuatorGroup.Walk).result shouldBe Right(())
      f.execute(app, Operation.Walk(0.2, 0, 0))
      f.expectCall("motion.walk").replyTo ! CallResult(1, "motion.walk", Right(None))
      (1 to settings.batteryReadings).foreach(_ =>
        f.publish ! RobotStatusUpdated(RobotSnapshot(1, robotAddress, batteryVoltage = Some(10.5), online = true)))
      events.expectMessageType[AppEvent.SafetyStop]
      val first = f.expectCall("motion.stop")
      // The app lets go of the walk lease, and more low readings come: one stop in flight is enough.
      f.middleware ! RobotMiddleware.Release(app, 1, ActuatorGroup.Walk)
      (1 to settings.batteryReadings).foreach(_ =>
        f.publish ! RobotStatusUpdated(RobotSnapshot(1, robotAddress, batteryVoltage = Some(10.4), online = true)))
      f.response.expectNoMessage(300.millis)
      first.replyTo ! CallResult(1, "motion.stop", Right(None))
      f.expectCall("motion.posture").call.params shouldBe Vector(RpcValue.Text("sit"))
    }
    "send a new link-figures watcher the current figures at once, not one interval later" in {
      val f = new Fixture(middlewareSettings = settings.copy(linkStatsInterval = 1.hour))
      val watcher = createTestProbe[LinkStats]()
      f.middleware ! RobotMiddleware.WatchLinkStats(1, watcher.ref)
      watcher.expectMessage(linkStats)
    }
    "refuse an operation without the lease it needs, and run it once the lease is held" in {
      val f = new Fixture
      val (app, _) = f.app("teleop", 1)
      f.execute(app, Operation.Head(0.3, 0.0)).expectMessageType[CallResult].result shouldBe
        Left(RobotFailure.LeaseNotHeld(1, ActuatorGroup.Head, None))
      f.acquire(app, ActuatorGroup.Head).result shouldBe Right(())
      val result = f.execute(app, Operation.Head(0.3, 0.0))
      val call = f.expectCall("motion.head")
      call.call.params shouldBe Vector(RpcValue.Number(0.3f), RpcValue.Number(0f))
      call.replyTo ! CallResult(1, "motion.head", Right(Some(RpcValue.Flag(true))))
      result.expectMessage(CallResult(1, "motion.head", Right(Some(RpcValue.Flag(true)))))
    }
    "hand a plain operation's reply ref to the robot's command owner, and relay only a walk's and a posture's answer" in {
      val f = new Fixture
      val (app, _) = f.app("teleop", 1)
      f.acquireAll(app, ActuatorGroup.Head, ActuatorGroup.Walk).result shouldBe Right(())
      // Plain: no bookkeeping after the answer, so the owner answers the app itself (no hop back through the guard),
      // and what it says, a superseded call included, reaches the app as it is (RobotInterface maps it for apps).
      val head = f.execute(app, Operation.Head(0.1, 0.0))
      val headCall = f.expectCall("motion.head")
      headCall.replyTo shouldBe head.ref
      headCall.replyTo ! CallResult(1, "motion.head", Left(RobotFailure.Superseded(1, "motion.head")))
      head.expectMessage(CallResult(1, "motion.head", Left(RobotFailure.Superseded(1, "motion.head"))))
      val raw = f.execute(app, Operation.RawCall("system", "ping", Vector.empty))
      f.expectCall("system.ping").replyTo shouldBe raw.ref
      // A walk's answer starts the refresh and a posture's failure stops the robot: both come back through the guard.
      val walk = f.execute(app, Operation.Walk(0.2, 0, 0))
      val walkCall = f.expectCall("motion.walk")
      walkCall.replyTo should not be walk.ref
      walkCall.replyTo ! CallResult(1, "motion.walk", Left(RobotFailure.Superseded(1, "motion.walk")))
      walk.expectMessage(
        CallResult(1, "motion.walk", Left(RobotFailure.Overloaded(1, "motion.walk replaced by a newer one"))))
      val posture = f.execute(app, Operation.Posture(Posture.Stand))
      val postureCall = f.expectCall("motion.posture")
      postureCall.replyTo should not be posture.ref
      postureCall.replyTo ! CallResult(1, "motion.posture", Left(RobotFailure.RobotError(1, "fell")))
      posture.expectMessage(CallResult(1, "motion.posture", Left(RobotFailure.RobotError(1, "fell"))))
      f.expectCall("motion.stop")
    }
    "let different apps hold different groups of one robot" in {
      val f = new Fixture
      val (walker, _) = f.app("walker", 1)
      val (looker, _) = f.app("looker", 1)
      f.acquire(walker, ActuatorGroup.Walk).result shouldBe Right(())
      f.acquire(looker, ActuatorGroup.Head).result shouldBe Right(())
      f.execute(looker, Operation.Walk(0.1, 0, 0)).receiveMessage().result shouldBe
        Left(RobotFailure.LeaseNotHeld(1, ActuatorGroup.Walk, Some("walker")))
    }
    "let a higher priority preempt a lease, tell the loser, and refuse equal priority" in {
      val f = new Fixture
      val (low, lowEvents) = f.app("follower", 1)
      val (equal, _) = f.app("other", 1)
      val (high, _) = f.app("referee", 5)
      f.acquire(low, ActuatorGroup.Walk).result shouldBe Right(())
      f.acquire(equal, ActuatorGroup.Walk).result shouldBe Left(RobotFailure.LeaseNotHeld(1, ActuatorGroup.Walk,
          Some("follower")))
      f.acquire(high, ActuatorGroup.Walk).result shouldBe Right(())
      lowEvents.expectMessage(AppEvent.LeasePreempted(1, ActuatorGroup.Walk, "referee"))
      f.execute(low, Operation.Stop()).receiveMessage().result shouldBe Left(RobotFailure.LeaseNotHeld(1,
          ActuatorGroup.Walk, Some("referee")))
    }
    "take a set of groups as one: refused when one is held at higher priority, and then nothing is taken" in {
      val f = new Fixture
      val (follower, followerEvents) = f.app("follower", 1)
      val (referee, _) = f.app("referee", 5)
      val (coach, coachEvents) = f.app("coach", 3)
      f.acquire(follower, ActuatorGroup.Walk).result shouldBe Right(())
      f.acquire(referee, ActuatorGroup.Head).result shouldBe Right(())
      // Arms are free and walk would be preempted, but head is held above the coach's priority.
      val refused = f.acquireAll(coach, ActuatorGroup.Arms, ActuatorGroup.Walk, ActuatorGroup.Head)
      refused shouldBe RobotMiddleware.LeaseResult(1,
        Set[ActuatorGroup](ActuatorGroup.Arms, ActuatorGroup.Walk, ActuatorGroup.Head),
        Left(RobotFailure.LeaseNotHeld(1, ActuatorGroup.Head, Some("referee"))))
      // Nothing was taken: the follower was not preempted nor its robot stopped, the free group is still free.
      followerEvents.expectNoMessage(200.millis)
      coachEvents.expectNoMessage(Duration.Zero)
      f.response.expectNoMessage(Duration.Zero)
      f.execute(coach, Operation.Arms(0, 0, 0, 0)).receiveMessage().result shouldBe
        Left(RobotFailure.LeaseNotHeld(1, ActuatorGroup.Arms, None))
      f.execute(coach, Operation.Stop()).receiveMessage().result shouldBe
        Left(RobotFailure.LeaseNotHeld(1, ActuatorGroup.Walk, Some("follower")))
      val (other, _) = f.app("other", 0)
      f.acquire(other, ActuatorGroup.Arms).result shouldBe Right(())
    }
    "take a set of groups as one when each is free or held lower, preempting the lower holder" in {
      val f = new Fixture
      val (follower, followerEvents) = f.app("follower", 1)
      val (coach, _) = f.app("coach", 3)
      f.acquire(follower, ActuatorGroup.Walk).result shouldBe Right(())
      f.acquireAll(coach, ActuatorGroup.Walk, ActuatorGroup.Head).result shouldBe Right(())
      followerEvents.expectMessage(AppEvent.LeasePreempted(1, ActuatorGroup.Walk, "coach"))
      f.expectCall("motion.stop") // taking walk stops the robot before the new holder steers it
      f.execute(coach, Operation.Head(0.1, 0)) // the head lease is the coach's: the call reaches the robot
      f.expectCall("motion.head")
      f.execute(follower, Operation.Stop()).receiveMessage().result shouldBe
        Left(RobotFailure.LeaseNotHeld(1, ActuatorGroup.Walk, Some("coach")))
    }
    "keep a walk alive inside the robot's lease, and stop the robot when its app dies, freeing the lease" in {
      val f = new Fixture
      val (app, _) = f.app("walker", 1)
      f.acquire(app, ActuatorGroup.Walk).result shouldBe Right(())
      f.execute(app, Operation.Walk(0.2, 0, 0))
      f.expectCall("motion.walk").replyTo ! CallResult(1, "motion.walk", Right(Some(RpcValue.Flag(true))))
      // Refreshes go through the robot's one command owner too, every 200 ms, each sent once (no retries).
      val refreshes = (1 to 3).map(_ => f.expectCall("motion.walk"))
      refreshes.foreach(_.idempotent shouldBe Some(false))
      testKit.stop(app)
      val stop = f.expectCall("motion.stop")
      stop.priority shouldBe Priority.Safety
      val (next, _) = f.app("next", 0)
      f.acquire(next, ActuatorGroup.Walk).result shouldBe Right(())
    }
    "send one stop however often the robot seems to come back while the stop is unanswered (no stop flood)" in {
      val f = new Fixture()
      val (app, _) = f.app("walker", 1)
      f.acquire(app, ActuatorGroup.Walk).result shouldBe Right(())
      (1 to 50).foreach { _ =>
        f.publish ! RobotOffline(1, "forged")
        f.publish ! RobotOnline(1, robotAddress)
      }
      val stop = f.expectCall("motion.stop")
      f.response.expectNoMessage(300.millis)
      stop.replyTo ! CallResult(1, "motion.stop", Right(None))
      // Answered: the next time the robot comes back it gets its stop again.
      f.publish ! RobotOffline(1, "again")
      f.publish ! RobotOnline(1, robotAddress)
      f.expectCall("motion.stop")
    }
    "not stop a robot for one low battery reading among good ones (a forged keep-alive cannot drive safety)" in {
      val f = new Fixture()
      val (app, events) = f.app("walker", 1)
      f.acquire(app, ActuatorGroup.Walk).result shouldBe Right(())
      (1 to 3 * settings.batteryReadings).foreach { i =>
        val volts = if (i % settings.batteryReadings == 0) 10.0 else 12.0
        f.publish ! RobotStatusUpdated(RobotSnapshot(1, robotAddress, batteryVoltage = Some(volts), online = true))
      }
      events.expectNoMessage(300.millis)
      f.response.expectNoMessage(300.millis)
    }
    "stop and sit a robot whose battery runs low, refuse motion until it recovers, and tell the lease holders" in {
      val f = new Fixture
      val (app, events) = f.app("walker", 1)
      f.acquire(app, ActuatorGroup.Walk).result shouldBe Right(())
      f.acquire(app, ActuatorGroup.Head).result shouldBe Right(())
      f.execute(app, Operation.Walk(0.2, 0, 0)) // established a guard and a walk
      f.expectCall("motion.walk").replyTo ! CallResult(1, "motion.walk", Right(None))
      (1 to settings.batteryReadings).foreach(_ =>
        f.publish ! RobotStatusUpdated(RobotSnapshot(1, robotAddress, batteryVoltage = Some(10.5), online = true)))
      events.expectMessageType[AppEvent.SafetyStop].reason should include("battery low")
      // The hold says how it ends, and robotctl's table shows it with the lease holders.
      val held = f.holds().loneElement
      held.leases shouldBe Map(ActuatorGroup.Walk -> "walker", ActuatorGroup.Head -> "walker")
      held.safetyHold.get should include("it clears by itself once 5 keep-alives in a row read above 11.00 V")
      held.safetyHold.get should include("robotctl battery <id> swap")
      f.expectCall("motion.stop").replyTo ! CallResult(1, "motion.stop", Right(None))
      f.expectCall("motion.posture").call.params shouldBe Vector(RpcValue.Text("sit"))
      f.execute(app, Operation.Walk(0.1, 0, 0)).receiveMessage().result.left.toOption.get shouldBe a[
        RobotFailure.SafetyHold]
      f.execute(app, Operation.Posture(Posture.Stand)).receiveMessage().result.left.toOption.get shouldBe a[
        RobotFailure.SafetyHold]
      f.execute(app, Operation.Head(0.1, 0.0))
      f.expectCall("motion.head")
      (1 to settings.batteryReadings).foreach(_ =>
        f.publish ! RobotStatusUpdated(RobotSnapshot(1, robotAddress, batteryVoltage = Some(11.5), online = true)))
      events.expectMessage(AppEvent.SafetyCleared(1))
      f.holds().loneElement.safetyHold shouldBe None
      f.execute(app, Operation.Walk(0.1, 0, 0))
      f.expectCall("motion.walk")
    }
    "let any app read a robot whose walk another app holds: reads need no lease (the method table's reads)" in {
      val f = new Fixture
      val (holder, _) = f.app("referee", 9)
      val (reader, _) = f.app("reader", 1)
      f.acquire(holder, ActuatorGroup.Walk).result shouldBe Right(())
      f.holds() shouldBe Vector(RobotHolds(1, Map(ActuatorGroup.Walk -> "referee"), None))
      naogateway.wire.RpcMethod.all.filter(_.read).map(_.name) shouldBe
        Vector("motion.getPosture", "system.battery", "system.ping")
      naogateway.wire.RpcMethod.all.filter(_.read).foreach { m =>
        val read = f.execute(reader, Operation.RawCall(m.module, m.method, Vector.empty))
        f.expectCall(m.name).replyTo ! CallResult(1, m.name, Right(Some(RpcValue.Text("sit"))))
        read.receiveMessage().result shouldBe Right(Some(RpcValue.Text("sit")))
      }
      // A call that is not a read still needs the lease, and names its holder.
      f.execute(reader, Operation.RawCall("motion", "walk", Vector.fill(3)(RpcValue.Number(0.1f))))
        .receiveMessage().result shouldBe Left(RobotFailure.LeaseNotHeld(1, ActuatorGroup.Walk, Some("referee")))
    }
    "refuse an argument out of range before the robot hears it, naming the argument, its value and what is allowed" in {
      val f = new Fixture
      val (app, _) = f.app("walker", 1)
      f.acquireAll(app, ActuatorGroup.Walk, ActuatorGroup.Head, ActuatorGroup.Arms).result shouldBe Right(())
      def refused(operation: Operation): String =
        f.execute(app, operation).receiveMessage().result.left.toOption.get match {
          case RobotFailure.RobotError(1, text) => text
          case other                            => fail(s"not refused as out of range: $other")
        }
      refused(Operation.Walk(100, 0, 0)) shouldBe "out of range: vx 100.0, allowed -0.3..0.3"
      refused(Operation.Walk(0.1, -0.5, 0)) shouldBe "out of range: vy -0.5, allowed -0.3..0.3"
      refused(Operation.Walk(0, 0, 3)) shouldBe "out of range: omega 3.0, allowed -1.0..1.0"
      refused(Operation.Head(0, 0.8)) shouldBe "out of range: tilt 0.8, allowed -0.6..0.5"
      refused(Operation.Arms(0, 0, 7, 0)) shouldBe "out of range: rightShoulder 7.0, allowed -3.142..3.142"
      // A raw call of the same method is read the same way (robotctl call, the doors' other calls).
      refused(Operation.RawCall("motion", "walk",
          Vector(RpcValue.Number(100f), RpcValue.Number(0f),
            RpcValue.Number(0f)))) shouldBe "out of range: vx 100.0, allowed -0.3..0.3"
      refused(Operation.RawCall("motion", "head", Vector(RpcValue.Number(2.5f), RpcValue.Number(0f)))) shouldBe
        "out of range: pan 2.5, allowed -2.0..2.0"
      // Nothing of the above reached the robot: the next call it hears is the walk inside the limits.
      f.execute(app, Operation.Walk(0.3, 0, -1.0))
      f.response.receiveMessage().call.name shouldBe "motion.walk"
    }
    "refresh a walk only once the robot has confirmed it, so a walk the robot refuses is never sent again" in {
      val f = new Fixture
      val (app, _) = f.app("walker", 1)
      f.acquire(app, ActuatorGroup.Walk).result shouldBe Right(())
      val result = f.execute(app, Operation.Walk(0.2, 0, 0))
      val walk = f.expectCall("motion.walk")
      // The robot takes several refresh periods to answer: a refresh sent meanwhile would repeat a walk it may refuse.
      f.response.expectNoMessage(settings.walkRefresh * 3)
      walk.replyTo ! CallResult(1, "motion.walk", Left(RobotFailure.RobotError(1, "not standing: sit")))
      result.receiveMessage().result shouldBe Left(RobotFailure.RobotError(1, "not standing: sit"))
      // The guard has handled the refusal (it answered above), so from here on only a refresh timer could send.
      f.response.expectNoMessage(1.second)
    }
    "refuse raw arm and walk calls under a safety hold too" in {
      val f = new Fixture
      val (app, events) = f.app("x", 1)
      f.acquire(app, ActuatorGroup.Arms).result shouldBe Right(())
      f.acquire(app, ActuatorGroup.Walk).result shouldBe Right(())
      (1 to settings.batteryReadings).foreach(_ =>
        f.publish ! RobotStatusUpdated(RobotSnapshot(1, robotAddress, batteryVoltage = Some(10.0), online = true)))
      events.expectMessageType[AppEvent.SafetyStop]
      val arms = Operation.RawCall("motion", "arms", Vector.fill(4)(RpcValue.Number(0f)))
      f.execute(app, arms).receiveMessage().result.left.toOption.get shouldBe a[RobotFailure.SafetyHold]
      f.execute(app, Operation.RawCall("motion", "walk", Vector.fill(3)(RpcValue.Number(0f)))).receiveMessage()
        .result.left.toOption.get shouldBe a[RobotFailure.SafetyHold]
    }
    "fail operations fast while the robot is offline, and stop it when it comes back" in {
      val f = new Fixture
      val (app, _) = f.app("walker", 1)
      f.acquire(app, ActuatorGroup.Walk).result shouldBe Right(())
      f.publish ! RobotOffline(1, "test")
      f.execute(app, Operation.Walk(0.1, 0, 0)).receiveMessage().result shouldBe Left(RobotFailure.RobotOffline(1))
      f.publish ! RobotOnline(1, robotAddress)
      f.expectCall("motion.stop").priority shouldBe Priority.Safety
    }
    "take the robot actor's word on reachability over the one it was created with (a restarted guard's)" in {
      // The middleware heard RobotOnline, but the robot actor, which owns reachability, says offline: that counts.
      val f = new Fixture(snapshotOnline = Some(false))
      val (app, _) = f.app("walker", 1)
      f.acquire(app, ActuatorGroup.Walk).result shouldBe Right(())
      f.execute(app, Operation.Walk(0.1, 0, 0)).receiveMessage().result shouldBe Left(RobotFailure.RobotOffline(1))
      f.response.expectNoMessage(200.millis)
    }
    "stop a robot that came back while its guard was still connecting, once the guard is ready" in {
      // The robot actor, asked by the new guard, knows the robot is offline.
      val f = new Fixture(holdConnect = true, snapshotOnline = Some(false))
      val (app, _) = f.app("walker", 1)
      val robotEvents = createTestProbe[RobotEvent]()
      f.middleware ! RobotMiddleware.WatchEvents(robotEvents.ref)
      f.publish ! RobotOffline(1, "test")
      val lease = createTestProbe[RobotMiddleware.LeaseResult]()
      f.middleware ! RobotMiddleware.Acquire(app, 1, ActuatorGroup.Walk, lease.ref)
      // The guard exists (it asked for the robot's children) and waits for them.
      val guardConnect = f.connects.receiveMessage()
      f.publish ! RobotOnline(1, robotAddress)
      // The middleware tells the guard before it tells the watchers: once the watcher has RobotOnline, the guard's
      // mailbox holds it ahead of the children sent next.
      robotEvents.expectMessage(RobotOffline(1, "test"))
      robotEvents.expectMessage(RobotOnline(1, robotAddress))
      guardConnect ! f.connected
      f.expectCall("motion.stop").priority shouldBe Priority.Safety
      lease.receiveMessage().result shouldBe Right(())
    }
    "not stop a robot on an online event older than what the guard knows (no stop overtaking an app's first command)" in {
      val f = new Fixture()
      val (app, _) = f.app("walker", 1)
      f.acquire(app, ActuatorGroup.Walk).result shouldBe Right(())
      // The guard asked the robot actor: online. The gateway's RobotOnline of first contact reaches it afterwards.
      f.publish ! RobotOnline(1, robotAddress)
      val done = createTestProbe[CallResult]()
      f.middleware ! RobotMiddleware.Execute(app, 1, Operation.Posture(Posture.Stand), done.ref)
      val seen = f.response.fishForMessage(3.seconds) {
        case c: RobotAccess.Call if c.call.name == "motion.posture" =>
          akka.actor.testkit.typed.FishingOutcome.Complete
        case _ => akka.actor.testkit.typed.FishingOutcome.Continue
      }
      seen.collect { case c: RobotAccess.Call => c.call.name } should not contain "motion.stop"
      val posture = seen.last.asInstanceOf[RobotAccess.Call]
      f.response.expectNoMessage(300.millis)
      posture.replyTo ! CallResult(1, "motion.posture", Right(None))
      done.receiveMessage().result shouldBe Right(None)
    }
    "list robots as the gateway answers, keeping no copy that events could leave behind" in {
      val configured =
        RobotSnapshot(7, new InetSocketAddress("192.168.1.107", 3838), online = false, quality = LinkQuality.Offline)
      val f = new Fixture(known = Vector(configured))
      val robots = createTestProbe[RobotMiddleware.RobotList]()
      f.middleware ! RobotMiddleware.ListRobots(robots.ref)
      robots.receiveMessage() shouldBe RobotMiddleware.RobotList(Vector(configured))
      // An event about the robot changes nothing the middleware answers with: the gateway (its robot actor) owns it.
      f.publish ! RobotStatusUpdated(configured.copy(batteryVoltage = Some(12.2), online = true))
      f.publish ! RobotOnline(7, configured.address)
      f.middleware ! RobotMiddleware.ListRobots(robots.ref)
      robots.receiveMessage() shouldBe RobotMiddleware.RobotList(Vector(configured))
    }
    "start a status watcher with the gateway's current snapshots, then stream keep-alives" in {
      val configured = RobotSnapshot(7, new InetSocketAddress("192.168.1.107", 3838))
      val other = RobotSnapshot(8, new InetSocketAddress("192.168.1.108", 3838))
      val f = new Fixture(known = Vector(configured, other))
      val watcher = createTestProbe[RobotSnapshot]()
      f.middleware ! RobotMiddleware.WatchStatus(Some(7), watcher.ref)
      watcher.expectMessage(configured)
      val next = configured.copy(batteryVoltage = Some(12.2), online = true, quality = LinkQuality.Good)
      f.publish ! RobotStatusUpdated(other)
      f.publish ! RobotStatusUpdated(next)
      watcher.expectMessage(next)
      watcher.expectNoMessage(100.millis)
    }
    "answer for robots the gateway does not know" in {
      val f = new Fixture
      val (app, _) = f.app("x", 1)
      val result = createTestProbe[CallResult]()
      f.middleware ! RobotMiddleware.Execute(app, 99, Operation.Say("hi"), result.ref)
      result.receiveMessage().result shouldBe Left(RobotFailure.UnknownRobot(99))
    }
    "map call failures to typed robot failures" in {
      val f = new Fixture
      val (app, _) = f.app("x", 1)
      f.acquire(app, ActuatorGroup.Speech).result shouldBe Right(())
      val result = f.execute(app, Operation.Say("hi"))
      f.expectCall("speech.say").replyTo ! CallResult(1, "speech.say", Left(RobotFailure.RuleGate("rule")))
      result.receiveMessage().result shouldBe Left(RobotFailure.RuleGate("rule"))
      val raw = f.execute(app, Operation.RawCall("system", "battery", Vector.empty))
      f.expectCall("system.battery").replyTo ! CallResult(1, "system.battery", Left(RobotFailure.RobotError(1, "flat")))
      raw.receiveMessage().result shouldBe Left(RobotFailure.RobotError(1, "flat"))
      RpcCall("system", "battery", Vector.empty).name shouldBe "system.battery"
    }
  }
}
