package naogateway.gateway.robot

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ManualTime, ScalaTestWithActorTestKit, TestProbe}
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, Behavior, BehaviorInterceptor, TypedActorContext}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.api.LinkQuality
import naogateway.gateway.HeartbeatSettings
import naogateway.gateway.link.PortProgress
import naogateway.gateway.robot.HeartBeatActor._
import naogateway.api.Priority

class HeartBeatActorSpec extends ScalaTestWithActorTestKit(ManualTime.config) with AnyWordSpecLike with LogCapturing {
  private val manualTime = ManualTime()
  private val settings = HeartbeatSettings(200.millis, 400.millis, 150.millis, 3, 2.seconds, 0.8, 0.9)

  /** Tells `handled` of each quality tick once the heartbeat has handled it (it reads the keep-alive count then). */
  private final class AckTicks(handled: ActorRef[Command]) extends BehaviorInterceptor[Command, Command] {
    def aroundReceive(ctx: TypedActorContext[Command], msg: Command, target: BehaviorInterceptor.ReceiveTarget[Command])
        : Behavior[Command] = {
      val next = target(ctx, msg)
      if (msg == QualityTick) handled ! msg
      next
    }
  }

  /** The robot actor's side of the keep-alives, on a clock that follows the manual time as the test moves it. */
  private final class Robot {
    @volatile var now = 0L
    val keepAlives = new KeepAlives(() => now)

    /** Time passes for the heartbeat's timers, then for the keep-alives' clock: a check handled in between reads a
      * clock behind its timers and re-arms later, never sooner, than it would on one clock.
      */
    def passes(d: FiniteDuration): Unit = {
      manualTime.timePasses(d)
      now += d.toNanos
    }

    /** A keep-alive now: counted, and told to `heartbeat` when it asks to be told (as the robot actor does). */
    def keepAlive(heartbeat: ActorRef[Command]): Unit = if (keepAlives.seen(now)) heartbeat ! KeepAliveSeen
  }

  /** A heartbeat of `robot` whose quality ticks are acknowledged to the returned probe. */
  private def acknowledging(reports: TestProbe[Any], online: Boolean, robot: Robot,
      s: HeartbeatSettings = settings): (ActorRef[Command], TestProbe[Command]) = {
    val handled = createTestProbe[Command]()
    val heartbeat = spawn(Behaviors.intercept(() => new AckTicks(handled.ref))(HeartBeatActor(s, reports.ref,
          reports.ref, online, robot.keepAlives)))
    heartbeat -> handled
  }

  /** An online heartbeat of `robot` reading `port` (its quality window longer than the tests that use it, so the link
    * quality is not judged), once it has reported `CameOnline`.
    */
  private def onlineReading(reports: TestProbe[Any], robot: Robot, port: PortProgress): Unit = {
    spawn(HeartBeatActor(settings.copy(qualityWindow = 10.seconds), reports.ref, reports.ref, online = true,
        robot.keepAlives, port))
    reports.expectMessage(CameOnline)
  }

  /** One probe, submitted straight to the robot's sender (here the same probe as the reports, to keep their order). */
  private def probeId(r: Any): Long = r match {
    case NoResponseActor.Submit(RobotFrames.Outbound.CallOut(call), Priority.Heartbeat, key, _, None, None) =>
      key shouldBe call.callId
      call.callId.get
    case other => fail(s"expected a probe, got $other")
  }

  "HeartBeatActor" must {
    "start its probe ids at a random point in every incarnation" in {
      val firsts = (1 to 2).map { _ =>
        val reports = createTestProbe[Any]()
        val heartbeat = spawn(HeartBeatActor(settings, reports.ref, reports.ref, online = false, new KeepAlives))
        heartbeat ! ProbeNow
        val id = probeId(reports.receiveMessage())
        CallId.ownerOf(id) shouldBe Some(CallId.Owner.Heartbeat)
        testKit.stop(heartbeat)
        CallId.count(id)
      }
      // Equal only with a chance of 1 in 2^30; a counter starting at 0 would give 1 both times.
      firsts.distinct.size shouldBe 2
    }
    "probe a quiet robot three times and then report it offline" in {
      val reports = createTestProbe[Any]()
      spawn(HeartBeatActor(settings, reports.ref, reports.ref, online = true, new KeepAlives))
      reports.expectMessage(CameOnline)
      manualTime.timePasses(399.millis)
      reports.expectNoMessage(Duration.Zero)
      manualTime.timePasses(1.milli)
      val first = probeId(reports.receiveMessage())
      CallId.ownerOf(first) shouldBe Some(CallId.Owner.Heartbeat)
      manualTime.timePasses(150.millis)
      probeId(reports.receiveMessage())
      manualTime.timePasses(150.millis)
      probeId(reports.receiveMessage())
      manualTime.timePasses(149.millis)
      reports.expectNoMessage(Duration.Zero)
      manualTime.timePasses(1.milli)
      reports.receiveMessage() shouldBe a[WentOffline]
      // Offline: no more probes until someone asks or the robot speaks.
      manualTime.timePasses(2.seconds)
      reports.expectNoMessage(Duration.Zero)
    }
    "stay online while keep-alives arrive, and recover when a probe is answered" in {
      val reports = createTestProbe[Any]()
      val robot = new Robot
      // A quality window longer than the test: the link quality is not judged here (the last test judges it).
      val (heartbeat, _) = acknowledging(reports, online = true, robot, settings.copy(qualityWindow = 10.seconds))
      reports.expectMessage(CameOnline)
      // Counted, not told: the heartbeat reads the count when its quiet check comes due.
      (1 to 10).foreach { _ =>
        robot.passes(200.millis)
        robot.keepAlives.seen(robot.now) shouldBe false
      }
      reports.expectNoMessage(Duration.Zero)
      /* Quiet from here: probed `quietAfter` after the last keep-alive (the check re-armed from it, handled in
       * between). */
      var quiet = 0.millis
      var probe: Option[Any] = None
      while (probe.isEmpty && quiet < 1.second) {
        robot.passes(10.millis)
        quiet += 10.millis
        probe = scala.util.Try(reports.receiveMessage(50.millis)).toOption
      }
      quiet should (be >= 400.millis and be <= 450.millis)
      val id = probeId(probe.get)
      heartbeat ! ProbeAnswered(id)
      reports.expectMessage(NoResponseActor.Finished(id))
      reports.receiveMessage() shouldBe a[ProbeRoundTrip]
      robot.passes(399.millis)
      reports.expectNoMessage(Duration.Zero)
    }
    "come back online when a keep-alive arrives while probing, told as the robot actor tells it" in {
      val reports = createTestProbe[Any]()
      val robot = new Robot
      val (heartbeat, _) = acknowledging(reports, online = true, robot)
      reports.expectMessage(CameOnline)
      robot.passes(400.millis)
      probeId(reports.receiveMessage())
      // Probing: a keep-alive is told, and the robot is back without being reported offline or online again.
      robot.passes(50.millis)
      robot.keepAlives.seen(robot.now) shouldBe true
      heartbeat ! KeepAliveSeen
      // Back online: the next quiet check is `quietAfter` away, not the probe's timeout.
      robot.passes(300.millis)
      reports.expectNoMessage(50.millis)
      robot.keepAlives.seen(robot.now) shouldBe false
    }
    "come back online on the next keep-alive, and probe on demand when offline" in {
      val reports = createTestProbe[Any]()
      val robot = new Robot
      val (heartbeat, _) = acknowledging(reports, online = false, robot)
      probeId(reports.receiveMessage())
      manualTime.timePasses(150.millis)
      probeId(reports.receiveMessage())
      manualTime.timePasses(150.millis)
      probeId(reports.receiveMessage())
      manualTime.timePasses(150.millis)
      manualTime.timePasses(1.second)
      reports.expectNoMessage(Duration.Zero)
      // Offline: a keep-alive is told, and brings the robot online.
      robot.keepAlive(heartbeat)
      reports.expectMessage(CameOnline)
      robot.passes(400.millis)
      probeId(reports.receiveMessage())
      robot.passes(150.millis)
      probeId(reports.receiveMessage())
      robot.passes(150.millis)
      probeId(reports.receiveMessage())
      robot.passes(150.millis)
      reports.receiveMessage() shouldBe a[WentOffline]
      robot.passes(1.second)
      heartbeat ! ProbeNow
      val id = probeId(reports.receiveMessage())
      heartbeat ! ProbeAnswered(id)
      reports.expectMessage(NoResponseActor.Finished(id))
      reports.receiveMessage() shouldBe a[ProbeRoundTrip]
      reports.expectMessage(CameOnline)
    }
    "back off rounds for a robot that never answers, however often it is wanted, and start again after an answer" in {
      val reports = createTestProbe[Any]()
      val heartbeat =
        spawn(HeartBeatActor(settings.copy(probeBackoffMax = 2.seconds), reports.ref, reports.ref, online = false,
            new KeepAlives))
      // One round: three probes 150 ms apart, then the last one's timeout.
      def silentRound(): Unit = {
        probeId(reports.receiveMessage())
        manualTime.timePasses(150.millis)
        probeId(reports.receiveMessage())
        manualTime.timePasses(150.millis)
        probeId(reports.receiveMessage())
        manualTime.timePasses(150.millis)
      }
      def wantedAfter(backoff: FiniteDuration): Unit = {
        (1 to 5).foreach(_ => heartbeat ! ProbeNow)
        manualTime.timePasses(backoff - 1.milli)
        reports.expectNoMessage(50.millis)
        manualTime.timePasses(1.milli)
      }
      silentRound()
      // Wanted again and again: each round waits for the back-off, doubling from one round (450 ms) to the maximum.
      Seq(450.millis, 900.millis, 1800.millis, 2.seconds, 2.seconds).foreach { backoff =>
        wantedAfter(backoff)
        silentRound()
      }
      // An answer ends the back-off; the next silence starts it again from one round.
      wantedAfter(2.seconds)
      val answered = probeId(reports.receiveMessage())
      heartbeat ! ProbeAnswered(answered)
      // The heartbeat frees its probe's room in the robot's buffer itself.
      reports.expectMessage(NoResponseActor.Finished(answered))
      reports.receiveMessage() shouldBe a[ProbeRoundTrip]
      reports.expectMessage(CameOnline)
      manualTime.timePasses(400.millis)
      silentRound()
      reports.receiveMessage() shouldBe a[WentOffline]
      wantedAfter(450.millis)
      probeId(reports.receiveMessage())
    }
    "wait for the port's reader to catch up before counting a probe unanswered, and come back on what it finds" in {
      val reports = createTestProbe[Any]()
      val robot = new Robot
      // The reader last found the socket empty at 0 and is behind from then on: a burst fills the socket.
      val port = new PortProgress(() => robot.now)
      port.reading()
      onlineReading(reports, robot, port)
      robot.passes(400.millis)
      probeId(reports.receiveMessage())
      // The probe's timeout comes and goes, and half the grace with it: no second probe, no verdict.
      (1 to 50).foreach(_ => robot.passes(10.millis))
      reports.expectNoMessage(Duration.Zero)
      // The reader works through the burst: a keep-alive was waiting in it, and the socket is empty now.
      robot.keepAlives.seen(robot.now)
      port.caughtUp()
      (1 to 5).foreach(_ => robot.passes(10.millis))
      // Online all along: nothing to report, and no probe until it is quiet again.
      reports.expectNoMessage(Duration.Zero)
    }
    "count a probe unanswered once the reader has caught up, or the grace is over" in {
      val reports = createTestProbe[Any]()
      val robot = new Robot
      val port = new PortProgress(() => robot.now)
      port.reading()
      onlineReading(reports, robot, port)
      robot.passes(400.millis)
      probeId(reports.receiveMessage())
      robot.passes(200.millis)
      reports.expectNoMessage(Duration.Zero)
      // Caught up with nothing from the robot in the socket: the next look counts the miss and probes again.
      port.caughtUp()
      (1 to 3).foreach(_ => robot.passes(10.millis))
      probeId(reports.receiveMessage())
      // Behind again for good: each of the two chances left waits out the grace (1 s), then the robot is offline.
      robot.passes(10.millis)
      port.caughtUp()
      port.reading()
      var waited = 0.millis
      var offline = Option.empty[Any]
      var probes = 0
      while (offline.isEmpty && waited < 5.seconds) {
        robot.passes(50.millis)
        waited += 50.millis
        scala.util.Try(reports.receiveMessage(20.millis)).toOption.foreach {
          case w: WentOffline => offline = Some(w)
          case p              => probeId(p); probes += 1
        }
      }
      probes shouldBe 1
      offline shouldBe defined
      // Two timeouts (150 ms each) and two graces, not the 300 ms of two timeouts alone.
      waited should be >= 2.seconds
    }
    "judge a probe at once while the port's reader has nothing left to read" in {
      val reports = createTestProbe[Any]()
      val robot = new Robot
      // A quiet port: the reader read a datagram and then found the socket empty, long before the robot fell silent.
      val port = new PortProgress(() => robot.now)
      port.reading()
      port.caughtUp()
      onlineReading(reports, robot, port)
      robot.passes(400.millis)
      probeId(reports.receiveMessage())
      robot.passes(150.millis)
      probeId(reports.receiveMessage())
      robot.passes(150.millis)
      probeId(reports.receiveMessage())
      robot.passes(150.millis)
      reports.receiveMessage() shouldBe a[WentOffline]
    }
    "ignore answers to probes it did not send" in {
      val reports = createTestProbe[Any]()
      val heartbeat = spawn(HeartBeatActor(settings, reports.ref, reports.ref, online = true, new KeepAlives))
      reports.expectMessage(CameOnline)
      manualTime.timePasses(400.millis)
      val id = probeId(reports.receiveMessage())
      heartbeat ! ProbeAnswered(id + 1)
      // Not the probe it waits for, but a probe's answer all the same: its room is free.
      reports.expectMessage(NoResponseActor.Finished(id + 1))
      manualTime.timePasses(150.millis)
      probeId(reports.receiveMessage())
    }
    "report a degraded link with hysteresis instead of flapping" in {
      val reports = createTestProbe[Any]()
      val robot = new Robot
      val (_, ticks) = acknowledging(reports, online = true, robot, settings.copy(quietAfter = 1.second))
      reports.expectMessage(CameOnline)
      // One tick: `seen` keep-alives counted, then the tick handled before the next is counted.
      def tick(seen: Boolean): Unit = {
        if (seen) robot.keepAlives.seen(robot.now)
        robot.passes(200.millis)
        ticks.expectMessage(QualityTick)
      }
      // Every keep-alive for a full window: good, nothing reported.
      (1 to 10).foreach(_ => tick(seen = true))
      reports.expectNoMessage(Duration.Zero)
      // Every second keep-alive lost: 50 % over the window -> degraded once.
      (1 to 20).foreach(i => tick(seen = i % 2 == 0))
      reports.expectMessage(QualityChanged(LinkQuality.Degraded))
      reports.expectNoMessage(Duration.Zero)
      // 85 % is above the degraded threshold but not above the good one: still degraded.
      (1 to 20).foreach(i => tick(seen = i % 7 != 0))
      reports.expectNoMessage(Duration.Zero)
      // Back to good only after a whole window (10 ticks here) above 90 %: not after 10 ticks, but before 25.
      (1 to 10).foreach(_ => tick(seen = true))
      reports.expectNoMessage(Duration.Zero)
      (1 to 15).foreach(_ => tick(seen = true))
      reports.expectMessage(QualityChanged(LinkQuality.Good))
    }
  }
}
