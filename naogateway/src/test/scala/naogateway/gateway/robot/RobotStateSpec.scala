package naogateway.gateway.robot

import java.net.InetSocketAddress

import akka.actor.testkit.typed.scaladsl.TestInbox
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.gateway.robot.RobotFrames.{Arrival, Outbound, Route}
import naogateway.proto.{
  DebuggingCommands,
  DebuggingOption,
  DebuggingOptionList,
  DebuggingOptionNames,
  Response,
  RobotHealth,
  ServoState,
  ServoTelemetry,
  Status
}
import naogateway.wire.{HeaderForm, MessageContents, RpcCall, WireLimits}
import naogateway.api.{
  GatewayEvent,
  LinkQuality,
  Priority,
  RobotOffline,
  RobotOnline,
  RobotStatusUpdated,
  ServoReading,
  ServoReadings,
  SigningState,
  VisionFrame
}
import naogateway.gateway.Rejection

/** The robot actor's state and frames, without actors: each named transition, and the pure encoding. */
class RobotStateSpec extends AnyWordSpec with Matchers {

  private val address = new InetSocketAddress("127.0.0.7", 3838)
  private val second = 1000000000L
  private val window = 5 * second
  private def fresh(discovered: Boolean = false,
      subscribers: Option[Set[akka.actor.typed.ActorRef[GatewayEvent]]] = Some(Set.empty)) =
    RobotState.initial(7, address, ClockSync(), subscribers, discovered, keepAliveTimesKept = 27)

  private def keepAlive(s: RobotState, at: Long, boot: Int, uptime: Int): (RobotState, KeepAliveOutcome) =
    s.keepAliveSeen(Status(teamID = Some(1)), Some(RobotHealth(uptimeMs = Some(uptime), bootId = Some(boot))), at,
      window, 3)

  private def enable(names: String*) = DebuggingCommands(optionEnable = Some(DebuggingOptionNames(names)))

  "A robot's state" should {
    "count frames and bytes each way, and say when the header form changes" in {
      val (s1, changed1) = fresh().frameReceived(60, HeaderForm.Legacy)
      changed1 shouldBe false
      val (s2, changed2) = s1.frameReceived(70, HeaderForm.Compact)
      changed2 shouldBe true
      val s3 = s2.segmentReceived(30)
      s3.link.datagramsIn shouldBe 3
      s3.link.bytesIn shouldBe 160
      // What leaves is counted by the sender as it sends, and shown with the rest.
      val out = new SentFigures
      out.sent(40)
      out.sent(2)
      val stats = s3.linkStats(0L, window, second / 5, out)
      (stats.datagramsIn, stats.bytesIn, stats.datagramsOut, stats.bytesOut) shouldBe ((3L, 160L, 2L, 42L))
    }

    "count refusals per kind" in {
      val (s1, n1) = fresh().refused(Rejection.BadProtobuf)
      val (s2, n2) = s1.refused(Rejection.BadProtobuf)
      val (s3, n3) = s2.refused(Rejection.UnknownCallId)
      (n1, n2, n3) shouldBe ((1L, 2L, 1L))
      s3.linkStats(0L, window, second / 5, new SentFigures).rejected shouldBe Map(Rejection.BadProtobuf.name -> 2L,
        Rejection.UnknownCallId.name -> 1L)
    }

    "show a robot that must sign as unsigned after unsigned or badly signed frames, as signed after a verified one" in {
      val signing = RobotState.initial(7, address, ClockSync(), Some(Set.empty), discovered = false,
        keepAliveTimesKept = 27, signs = true)
      signing.view(online = false).signing shouldBe SigningState.Awaited
      val unsigned = signing.signatureRefused(Rejection.Unsigned)
      unsigned.view(online = false).signing shouldBe SigningState.Unsigned
      // A replay is anyone's doing: it changes nothing shown.
      signing.signatureRefused(Rejection.Replayed).snapshot.signing shouldBe SigningState.Awaited
      unsigned.signatureAccepted.snapshot.signing shouldBe SigningState.Signed
      // A forged frame beside the robot's own signed ones changes nothing shown; once it went offline, it does.
      val signed = unsigned.signatureAccepted
      signed.signatureRefused(Rejection.BadSignature).snapshot.signing shouldBe SigningState.Signed
      signed.signatureUnconfirmed.snapshot.signing shouldBe SigningState.Awaited
      signed.signatureUnconfirmed.signatureRefused(Rejection.BadSignature).snapshot.signing shouldBe
        SigningState.Unsigned
      // A robot that need not sign stays off, whatever arrives.
      fresh().signatureRefused(Rejection.Unsigned).signatureAccepted.snapshot.signing shouldBe SigningState.Off
    }

    "not pass a discovered robot's introducing keep-alive to the heartbeat, but every later one" in {
      val (s1, first) = keepAlive(fresh(discovered = true), second, boot = 1, uptime = 1000)
      first.heard shouldBe false
      keepAlive(s1, 2 * second, boot = 1, uptime = 2000)._2.heard shouldBe true
      keepAlive(fresh(), second, boot = 1, uptime = 1000)._2.heard shouldBe true
    }

    "take a new session after three keep-alives of it, and start its clock estimate afresh" in {
      val old = (1 to 10).foldLeft(fresh()) { (s, i) =>
        keepAlive(s, i * second / 5, boot = 1, uptime = 100000 + i * 200)._1
      }
      old.clockSync.samples should be > 1
      val (a, r1) = keepAlive(old, 3 * second, boot = 2, uptime = 100)
      val (b, r2) = keepAlive(a, 3 * second + second / 5, boot = 2, uptime = 300)
      val (c, r3) = keepAlive(b, 3 * second + 2 * second / 5, boot = 2, uptime = 500)
      Seq(r1, r2, r3).map(_.restarted) shouldBe Seq(false, false, true)
      c.snapshot.bootId shouldBe Some(2)
      c.clockSync.samples shouldBe 1
    }

    "keep the last servo telemetry over keep-alives without one, until the robot restarts or goes offline (6.8)" in {
      val telemetry = ServoTelemetry(Vector(ServoState(1, Some(512), Some(-40), Some(121), Some(41)),
          ServoState(2, silent = Some(true))), busErrors = Some(2))
      def withServos(s: RobotState, at: Long, boot: Int, uptime: Int, t: Option[ServoTelemetry]) =
        s.keepAliveSeen(Status(teamID = Some(1)), Some(RobotHealth(uptimeMs = Some(uptime), bootId = Some(boot))), at,
          window, 3, t)._1
      val s1 = withServos(fresh(), second, boot = 1, uptime = 1000, Some(telemetry))
      val read = s1.snapshot.servos.get
      read.receivedAtNanos shouldBe second
      read.busErrors shouldBe Some(2L)
      read.servos shouldBe Vector(ServoReading(1, Some(512), Some(-40), Some(12.1), Some(41)),
        ServoReading(2, silent = true))
      read.servos.head.degrees.get shouldBe 0.0 +- 1e-9
      // The next keep-alives carry none: the last telemetry stays, with its own time.
      val s2 = withServos(s1, second + second / 5, boot = 1, uptime = 1200, None)
      s2.snapshot.servos shouldBe Some(read)
      s2.snapshot.receivedAtNanos shouldBe second + second / 5
      s2.view(online = true).servos shouldBe Some(read)
      // Offline: gone.
      s2.wentOffline.snapshot.servos shouldBe None
      // A keep-alive of a new session (another bootId) without telemetry: gone at once.
      withServos(s2, 2 * second, boot = 2, uptime = 100, None).snapshot.servos shouldBe None
      // A new session by uptime alone (no bootId), confirmed after three keep-alives: gone then.
      def noBoot(s: RobotState, at: Long, uptime: Int, t: Option[ServoTelemetry]) =
        s.keepAliveSeen(Status(teamID = Some(1)), Some(RobotHealth(uptimeMs = Some(uptime))), at, window, 3, t)._1
      val old = (1 to 5).foldLeft(noBoot(fresh(), second, 100000, Some(telemetry))) { (s, i) =>
        noBoot(s, second + i * second / 5, 100000 + i * 200, None)
      }
      old.snapshot.servos.map(_.servos.size) shouldBe Some(2)
      val restarted = (1 to 3).foldLeft(old)((s, i) => noBoot(s, 3 * second + i * second / 5, i * 200, None))
      restarted.snapshot.servos shouldBe None
      // A new telemetry replaces the old one.
      val replaced = withServos(s2, 3 * second, boot = 1, uptime = 3000, Some(ServoTelemetry()))
      replaced.snapshot.servos shouldBe Some(ServoReadings(Vector.empty, None, 3 * second))
    }

    "hand a keep-alive's servo telemetry on with it" in {
      val t = ServoTelemetry(Vector(ServoState(3, Some(100))))
      RobotFrames.arrivals(7, MessageContents(7, status = Some(Status()), servoTelemetry = Some(t))) shouldBe
        Vector(Arrival.KeepAlive(Status(), None, Some(t)))
    }

    "keep a bounded number of keep-alive times and estimate the loss from them" in {
      val flooded = (1 to 1000).foldLeft(fresh()) { (s, i) =>
        keepAlive(s.frameReceived(60, HeaderForm.Legacy)._1, i * 1000000L, boot = 1, uptime = i)._1
      }
      flooded.link.keepAliveTimes.size should be <= 27
      fresh().link.lossEstimate(second, window, second / 5) shouldBe 1.0
      // Punctual keep-alives every 200 ms for 5 s: nothing lost.
      val punctual = (1 to 25).foldLeft(fresh()) { (s, i) =>
        keepAlive(s.frameReceived(60, HeaderForm.Legacy)._1, i * second / 5, boot = 1, uptime = i * 200)._1
      }
      punctual.link.lossEstimate(5 * second, window, second / 5) shouldBe 0.0 +- 0.05
      // Half of them missing over the same window: about half lost.
      val halved = (1 to 25 by 2).foldLeft(fresh()) { (s, i) =>
        keepAlive(s.frameReceived(60, HeaderForm.Legacy)._1, i * second / 5, boot = 1, uptime = i * 200)._1
      }
      halved.link.lossEstimate(5 * second, window, second / 5) shouldBe 0.5 +- 0.1
    }

    "keep the latest keep-alive times: at most the bound, none older than the window, the newest last" in {
      def kept(times: Seq[Long], now: Long, bound: Int) = ArrivalTimes(times: _*).appended(now, 100L, bound).toVector
      kept(Nil, 10L, 3) shouldBe Vector(10L)
      kept(Seq(10L, 20L), 30L, 3) shouldBe Vector(10L, 20L, 30L)
      kept(Seq(10L, 20L, 30L), 40L, 3) shouldBe Vector(20L, 30L, 40L)
      kept(Seq(10L, 20L, 30L), 40L, 1) shouldBe Vector(40L)
      // Older than the window: dropped, however many there are; the new time is always kept.
      kept(Seq(10L, 20L, 130L), 140L, 4) shouldBe Vector(130L, 140L)
      kept(Seq(10L, 20L), 500L, 4) shouldBe Vector(500L)
      kept(Seq(40L, 50L), 140L, 4) shouldBe Vector(40L, 50L, 140L)
      val times = ArrivalTimes(10L, 20L, 30L)
      (times.countFrom(0L), times.countFrom(20L), times.countFrom(21L), times.countFrom(31L)) shouldBe ((3, 2, 1, 0))
      (times.firstFrom(0L), times.firstFrom(21L)) shouldBe ((10L, 30L))
      times shouldBe ArrivalTimes(10L, 20L, 30L)
      ArrivalTimes.empty.size shouldBe 0
      // The latest value appends in place: two values made from the same one each keep their own times, and the one
      // they came from is unchanged.
      val base = ArrivalTimes(10L, 20L)
      val (a, b) = (base.appended(30L, 100L, 4), base.appended(35L, 100L, 4))
      (base.toVector, a.toVector, b.toVector) shouldBe ((Vector(10L, 20L), Vector(10L, 20L, 30L),
        Vector(10L, 20L, 35L)))
      a.appended(40L, 100L, 4).toVector shouldBe Vector(10L, 20L, 30L, 40L)
      // Across the copies a full buffer needs: the latest `kept`, in order.
      val many = (1L to 500L).foldLeft(ArrivalTimes.empty)((t, n) => t.appended(n, 1000L, 27))
      many.toVector shouldBe (474L to 500L).toVector
      many shouldBe ArrivalTimes(474L to 500L: _*)
    }

    "show the snapshot as it leaves the actor, the same value when nothing in it changes" in {
      val s = fresh()
      val offline = s.view(online = false)
      offline.online shouldBe false
      offline.quality shouldBe LinkQuality.Offline
      offline should be theSameInstanceAs s.snapshot
      val on = s.wentOnline
      val shown = on.view(online = true)
      (shown.online, shown.quality) shouldBe ((true, LinkQuality.Good))
      val again = on.copy(snapshot = shown).view(online = true)
      again should be theSameInstanceAs shown
      on.copy(snapshot = shown).view(online = false).quality shouldBe LinkQuality.Offline
    }

    "smooth round trips, count retransmissions, follow a rebound and show itself offline with an offline quality" in {
      val s =
        fresh().roundTrip(8000000L).roundTrip(16000000L).retransmitted.rebound(new InetSocketAddress("127.0.0.8", 3838))
      s.link.rttNanos shouldBe Some(9000000.0)
      s.link.retransmissions shouldBe 1
      s.address.getHostString shouldBe "127.0.0.8"
      s.snapshot.address shouldBe s.address
      val online = s.wentOnline
      online.view(online = true).quality shouldBe LinkQuality.Good
      online.view(online = false).quality shouldBe LinkQuality.Offline
      online.qualityChanged(LinkQuality.Degraded).view(online = true).quality shouldBe LinkQuality.Degraded
    }

    "hold option commands while the pulled list is awaited, then enable only what the robot offers" in {
      val pulling = fresh().pullStarted
      val (held, now) = pulling.optionCommand(enable("havimo.regions", "no.such"))
      now shouldBe false
      held.options.active shouldBe Set("havimo.regions", "no.such")
      held.optionCommand(DebuggingCommands(optionPull = Some(true)))._2 shouldBe true
      val (p1, k1) = held.pullSent
      val (p2, k2) = p1.pullSent
      Seq(k1, k2).foreach(_ should be < 0L)
      k1 should not be k2
      p2.options.pullKey shouldBe k2
      val (pushed, known, unknown) =
        p2.optionsPushed(Seq("status.text", "havimo.regions", "havimo.grid").map(n => DebuggingOption(name = n)))
      known shouldBe Vector("havimo.regions")
      unknown shouldBe Vector("no.such")
      pushed.options.pulling shouldBe false
      pushed.optionCommand(enable("status"))._2 shouldBe true
      // A later push (not answering a pull) enables nothing again.
      pushed.optionsPushed(Seq(DebuggingOption(name = "havimo.regions")))._2 shouldBe empty
    }

    "forget a disabled option with its sub-options" in {
      val s = fresh().optionCommand(enable("havimo", "havimo.grid", "status"))._1
        .optionCommand(DebuggingCommands(optionDisable = Some(DebuggingOptionNames(Seq("havimo")))))._1
      s.options.active shouldBe Set("status")
    }

    "hold events until the gateway names the subscribers, at most a bounded number, then hand them on in order" in {
      val events = TestInbox[GatewayEvent]()
      val waiting = fresh(subscribers = None)
      val (held, to) = waiting.publish(RobotOnline(7, address))
      to shouldBe empty
      val flooded = (1 to 100).foldLeft(held)((s, i) => s.publish(RobotOffline(7, s"$i"))._1)
      flooded.held.size shouldBe RobotState.HeldEvents
      val (known, out) = flooded.subscribersChanged(Set(events.ref))
      out.head shouldBe RobotOnline(7, address)
      out.size shouldBe RobotState.HeldEvents
      known.held shouldBe empty
      known.publish(RobotOffline(7, "x"))._2 shouldBe Set(events.ref)
    }

    "send a keep-alive's status to the subscribers that want it, every other event to all of them" in {
      val app = TestInbox[GatewayEvent]().ref
      val recorder = TestInbox[GatewayEvent]().ref
      val (both, _) = fresh(subscribers = None).subscribersChanged(Set(app, recorder), statusless = Set(recorder))
      both.publish(RobotStatusUpdated(both.view(online = true)))._2 shouldBe Set(app)
      both.publish(RobotOffline(7, "x"))._2 shouldBe Set(app, recorder)
      both.wantsStatus shouldBe true
      val (recorderOnly, _) = both.subscribersChanged(Set(recorder), statusless = Set(recorder))
      recorderOnly.wantsStatus shouldBe false
      recorderOnly.publish(RobotOffline(7, "x"))._2 shouldBe Set(recorder)
      fresh(subscribers = None).wantsStatus shouldBe true
    }

    "keep the camera registrations, saying which one is new" in {
      val a = TestInbox[VisionFrame]().ref
      val (s1, new1) = fresh().visionSubscribed(a, grid = false)
      val (s2, new2) = s1.visionSubscribed(a, grid = true)
      (new1, new2) shouldBe ((true, false))
      s2.vision shouldBe Map(a -> true)
      s2.visionGone(a).vision shouldBe empty
    }
  }

  "A robot's frames" should {
    val outbox = TestInbox[Outbox.Command]().ref
    val datagrams = Route.Datagrams(outbox, address, HeaderForm.Legacy, signs = true)
    val zeroMq = Route.ZeroMq(outbox, address, TestInbox[naogateway.gateway.link.ZeroMqRobotLink.Command]().ref)
    val call = Outbound.CallOut(RpcCall("system", "ping", Vector.empty, Some(5L)))

    "encode a call as an FU-Remote frame over datagrams and as a bare message over ZeroMQ" in {
      val frame = RobotFrames.encode(7, call, datagrams).toOption.get
      MessageContents.decodeFrame(frame).toOption.flatMap(_._2.rpcRequest).map(RpcCall.fromProto) shouldBe Some(
        call.call)
      val bare = RobotFrames.encode(7, call, zeroMq).toOption.get
      MessageContents.parse(bare).toOption.flatMap(_.rpcRequest).map(RpcCall.fromProto) shouldBe Some(call.call)
    }

    "refuse a segment over ZeroMQ and an oversize one over datagrams, and never sign a segment" in {
      RobotFrames.encode(7, Outbound.SegmentOut(Array[Byte](1)), zeroMq).isLeft shouldBe true
      RobotFrames.encode(7, Outbound.SegmentOut(new Array[Byte](WireLimits.MaxDatagramBytes + 1)), datagrams).isLeft shouldBe true
      RobotFrames.send(7, Outbound.SegmentOut(Array[Byte](1)), Array[Byte](1), datagrams, Priority.Command, None, 1L)
        .signed shouldBe false
      RobotFrames.send(7, call, Array[Byte](1), datagrams, Priority.Command, None, 1L).signed shouldBe true
      val viaLink = RobotFrames.send(7, call, Array[Byte](1), zeroMq, Priority.Command, None, 1L)
      (viaLink.signed, viaLink.via) shouldBe ((false, Some(zeroMq.link)))
    }

    "hand on a frame that carries a keep-alive only as that keep-alive, and a frame of nothing known as nothing" in {
      val health = RobotHealth(uptimeMs = Some(5))
      RobotFrames.arrivals(7,
        MessageContents(7, status = Some(Status(teamID = Some(1))), robotHealth = Some(health))) shouldBe
        Vector(Arrival.KeepAlive(Status(teamID = Some(1)), Some(health)))
      RobotFrames.arrivals(7, MessageContents(7)) shouldBe empty
      RobotFrames.arrivals(7, MessageContents(7, robotHealth = Some(health))) shouldBe empty
      // The keep-alive first, then what else the frame carries.
      val pushed = RobotFrames.arrivals(7,
        MessageContents(7, status = Some(Status()),
          debuggingCommands = Some(DebuggingCommands(optionPush = Some(DebuggingOptionList(Vector.empty))))))
      pushed.map(_.getClass.getSimpleName) shouldBe Vector("KeepAlive", "OptionsPushed")
    }

    "sort what a frame carries, a reply to nobody's call id refused" in {
      val contents = MessageContents(7, status = Some(Status(teamID = Some(1))),
        rpcResponse = Some(Response(callId = Some((1L << 30).toInt))))
      val arrivals = RobotFrames.arrivals(7, contents)
      arrivals.head shouldBe a[Arrival.KeepAlive]
      arrivals(1) shouldBe Arrival.Refused(Rejection.UnknownCallId, s"call id ${1L << 30}")
    }
  }
}
