package naogateway.gateway.robot

import java.net.{InetAddress, InetSocketAddress}

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, LoggingTestKit, ScalaTestWithActorTestKit}
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{Behavior, BehaviorInterceptor, SupervisorStrategy, TypedActorContext}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.RobotAccess
import naogateway.api.{GatewayEvent, LinkQuality, RobotOnline, RobotSnapshot, RobotStatusUpdated}
import naogateway.gateway.GatewaySettings
import naogateway.gateway.link.Backlog
import naogateway.gateway.recording.RobotClockEstimates
import naogateway.proto.Status
import naogateway.wire.{HeaderForm, MessageContents}

/** A robot actor publishes its own events to the gateway's subscribers and owns its snapshot and reachability. */
class RobotEventsSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {
  private val settings = GatewaySettings(system)
  private val address = new InetSocketAddress(InetAddress.getLoopbackAddress, 3838)

  private def keepAlive(battery: Int): RobotActor.FrameReceived =
    RobotActor.FrameReceived(MessageContents(4, status = Some(Status(teamID = Some(battery)))), HeaderForm.Legacy, 30)

  /** Throws once, when armed, on the next keep-alive: a stand-in for any bug in the robot actor. */
  private final class CrashOnce extends BehaviorInterceptor[Any, Any] {
    @volatile var armed = false
    def aroundReceive(
        ctx: TypedActorContext[Any], msg: Any, target: BehaviorInterceptor.ReceiveTarget[Any]): Behavior[Any] =
      msg match {
        case _: RobotActor.FrameReceived if armed =>
          armed = false
          throw new IllegalStateException("injected failure")
        case _ => target(ctx, msg)
      }
  }

  "A robot actor" must {
    "send its events to the subscribers the gateway gave it, and follow the gateway's later lists" in {
      val outbox = createTestProbe[Outbox.Command]()
      val first = createTestProbe[GatewayEvent]()
      val second = createTestProbe[GatewayEvent]()
      val backlog = new Backlog(8)
      val robot =
        spawn(RobotActor(4, address, settings, outbox.ref, RobotWiring(Set(first.ref), None, backlog), heard = true))
      first.expectMessage(RobotOnline(4, address))
      backlog.add()
      robot ! keepAlive(1)
      first.expectMessageType[RobotStatusUpdated].snapshot.teamId shouldBe Some(1)
      // Handled: its place in the backlog is free again.
      backlog.size shouldBe 0
      robot ! RobotActor.Subscribers(Set(second.ref))
      robot ! keepAlive(2)
      second.expectMessageType[RobotStatusUpdated].snapshot.teamId shouldBe Some(2)
      first.expectNoMessage(100.millis)
    }
    "put the clock estimate in the wiring's clocks, sending no status to a statusless subscriber (the recorder)" in {
      val outbox = createTestProbe[Outbox.Command]()
      val gateway = createTestProbe[RobotActor.SubscribersWanted]()
      val recorder = createTestProbe[GatewayEvent]()
      val app = createTestProbe[GatewayEvent]()
      val clocks = new RobotClockEstimates
      val robot = spawn(RobotActor(4, address, settings, outbox.ref,
          RobotWiring(Set.empty, Some(gateway.ref), new Backlog(64), clocks), heard = true))
      gateway.receiveMessage().robot ! RobotActor.Subscribers(Set(recorder.ref, app.ref), Set(recorder.ref))
      recorder.expectMessage(RobotOnline(4, address))
      app.expectMessage(RobotOnline(4, address))
      // Robot times 20 ms apart: enough keep-alives for an estimate (ClockSync.MinSamples).
      val times = (1 to 2 * ClockSync.MinSamples).map(_ * 20L)
      times.foreach { t =>
        robot ! RobotActor.FrameReceived(MessageContents(4, status = Some(Status(timestamp = Some(t)))),
          HeaderForm.Legacy, 30)
      }
      val last = times.map(_ => app.expectMessageType[RobotStatusUpdated].snapshot).last
      val estimate = last.clock.getOrElse(fail("no clock estimate after the keep-alives"))
      clocks.toGatewayNanos(4, 1000L) shouldBe Some(estimate.toGatewayNanos(1000L))
      clocks.toGatewayNanos(5, 1000L) shouldBe None
      recorder.expectNoMessage(100.millis)
    }
    "derive the snapshot's online from its own state, offline before the robot is reached" in {
      val outbox = createTestProbe[Outbox.Command]()
      val events = createTestProbe[GatewayEvent]()
      val robot = spawn(RobotActor(4, address, settings, outbox.ref, RobotWiring.to(events.ref), heard = false))
      val snapshots = createTestProbe[RobotSnapshot]()
      robot ! RobotAccess.GetSnapshot(snapshots.ref)
      val before = snapshots.receiveMessage()
      (before.online, before.quality) shouldBe ((false, LinkQuality.Offline))
      robot ! keepAlive(1)
      events.fishForMessage(5.seconds) {
        case RobotOnline(4, _) => akka.actor.testkit.typed.FishingOutcome.Complete
        case _                 => akka.actor.testkit.typed.FishingOutcome.ContinueAndIgnore
      }
      robot ! RobotAccess.GetSnapshot(snapshots.ref)
      val after = snapshots.receiveMessage()
      (after.online, after.quality, after.teamId) shouldBe ((true, LinkQuality.Good, Some(1)))
    }
    "ask the gateway for the subscribers on every start, holding its events until the answer comes" in {
      val outbox = createTestProbe[Outbox.Command]()
      val gateway = createTestProbe[RobotActor.SubscribersWanted]()
      val spawnedWith = createTestProbe[GatewayEvent]()
      val current = createTestProbe[GatewayEvent]()
      val crash = new CrashOnce
      val robot = spawn(
        Behaviors.supervise(
          Behaviors.intercept(() => crash)(
            RobotActor(4, address, settings, outbox.ref, RobotWiring(Set.empty, Some(gateway.ref), new Backlog(8)),
              heard = true))
        ).onFailure(SupervisorStrategy.restartWithBackoff(50.millis, 200.millis, 0.0))
      )
      gateway.receiveMessage().robot ! RobotActor.Subscribers(Set(spawnedWith.ref))
      spawnedWith.expectMessage(RobotOnline(4, address))
      crash.armed = true
      LoggingTestKit.error[IllegalStateException].withMessageContains("injected failure").expect {
        robot ! keepAlive(1)
      }
      // Meanwhile the subscriber list changed at the gateway; the new incarnation asks for it.
      gateway.receiveMessage(5.seconds).robot ! RobotActor.Subscribers(Set(current.ref))
      robot ! keepAlive(2)
      current.fishForMessage(5.seconds) {
        case RobotStatusUpdated(s) if s.teamId.contains(2) => akka.actor.testkit.typed.FishingOutcome.Complete
        case _                                             => akka.actor.testkit.typed.FishingOutcome.ContinueAndIgnore
      }
      spawnedWith.expectNoMessage(100.millis)
    }
  }
}
