package naogateway

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.actor.typed.scaladsl.{ActorContext, Behaviors, StashBuffer, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior}

import naogateway.link.{Backlog, ZeroMqRobotLink}
import naogateway.proto.{DebuggingCommands, DebuggingOption, DebuggingOptionNames}
import naogateway.wire._

/** The supervisor of one robot: owns its address, liveness, children and link figures, and re-syncs it after restarts. */
object RobotActor {

  /** What a robot actor accepts. */
  sealed trait Command

  /** A decoded FU-Remote frame from this robot (`size` bytes on the wire). */
  final case class FrameReceived(contents: MessageContents, form: HeaderForm, size: Int) extends Command

  /** A secure-stream segment from this robot's address. */
  final case class SegmentReceived(bytes: Array[Byte]) extends Command

  /** A datagram from this robot's address was refused, for this kind of reason. */
  final case class DatagramRejected(kind: Rejection) extends Command

  /** The robot was re-bound to another IP address (it moved host); `address` is where it receives now. */
  final case class Rebound(address: InetSocketAddress) extends Command

  /** Answers with the children's refs once the robot is reachable (probing it first if needed). */
  final case class Connect(replyTo: ActorRef[Connected]) extends Command

  /** Answers with the latest keep-alive contents and liveness. */
  final case class GetSnapshot(replyTo: ActorRef[RobotSnapshot]) extends Command

  /** Answers with the link figures. */
  final case class GetLinkStats(replyTo: ActorRef[LinkStats]) extends Command

  /** What the trusted GameController last said (a ZeroMQ robot's link applies the competition rule itself). */
  final case class GameStateChanged(reading: GameReading) extends Command

  /** Messages from the robot's own children. */
  sealed trait FromChild extends Command

  /** Sends `out` to the robot; the outbox's outcome goes to `outcome`, marked with `tag`. */
  final case class Transmit(out: Outbound, priority: Priority, outcome: Option[ActorRef[Outbox.Outcome]], tag: Long = 0L)
      extends FromChild

  /** The gateway's event subscribers now: this robot's events go to them directly, not through the gateway. */
  final case class Subscribers(subscribers: Set[ActorRef[GatewayEvent]]) extends Command

  /** A robot actor (re)started and asks the gateway for its current subscribers. */
  final case class SubscribersWanted(robot: ActorRef[Subscribers])

  /**
   * How a robot actor is wired to its gateway. With a `gateway`, the actor asks it for the subscribers on every start
   * (a restarted actor must not use the list it was spawned with) and holds its events until the answer comes; the
   * gateway pushes every later change itself. Without one, `subscribers` is the list. `backlog` counts the datagrams
   * the robot port's reader has handed the actor, given back as each is handled.
   */
  final case class Wiring(subscribers: Set[ActorRef[GatewayEvent]], gateway: Option[ActorRef[SubscribersWanted]], backlog: Backlog)

  /** Wirings without a gateway. */
  object Wiring {

    /** Events to `events` alone, no gateway to ask: for a robot actor on its own (tests). */
    def to(events: ActorRef[GatewayEvent]): Wiring = Wiring(Set(events), None, new Backlog(Int.MaxValue))
  }

  /** A caller wants the robot while it is offline: probe it now. */
  case object Wanted extends FromChild

  /** A clean round-trip sample. */
  final case class RoundTrip(nanos: Long) extends FromChild

  /** A call was sent again. */
  case object Retransmitted extends FromChild

  /** The response actor (re)started and asks for the robot's route; every later change is pushed to it. */
  final case class RouteWanted(replyTo: ActorRef[ResponseActor.RouteChanged]) extends FromChild

  /** The response actor sent a datagram of `bytes` straight to the outbox (or the ZeroMQ link): counted here. */
  final case class SentDirect(bytes: Int) extends FromChild

  /** A call actor (re)started and asks whether the robot is reachable now; a restart must not forget it is offline. */
  final case class ReachabilityWanted(replyTo: ActorRef[Boolean]) extends FromChild

  /** A stream subscribes to this robot's camera frames (through the vision actor, which this actor outlives). */
  final case class VisionSubscribe(subscriber: ActorRef[VisionFrame], grid: Boolean) extends FromChild

  /** The vision actor (re)started and asks for the registrations; every later change is pushed to it. */
  final case class VisionSubscribersWanted(replyTo: ActorRef[VisionActor.Subscribers]) extends FromChild

  private final case class HeartbeatReport(report: HeartBeatActor.Report) extends Command
  private final case class VisionSubscriberGone(subscriber: ActorRef[VisionFrame]) extends Command
  private final case class ZeroMqLinkEvent(event: ZeroMqRobotLink.Event) extends Command
  private case object PullOptions extends Command
  private case object PullKey
  private final case class Forget(reason: String) extends Command
  private case object ForgetKey

  /**
   * How often `optionPull` is repeated until the robot's `optionPush` arrives. Fixed, not a setting: protocol.md 8,
   * step 1 gives robots this period ("about every second"), and a robot's firmware is written against it.
   */
  val OptionPullInterval: FiniteDuration = 1.second

  /** How a robot is reached. */
  sealed trait Transport extends Product with Serializable

  /** The two kinds of robot. */
  object Transport {

    /** FU-Remote frames in UDP datagrams through the gateway's outbox: the CM-530. */
    case object Datagrams extends Transport

    /** Serialized `Message`s to a ZeroMQ REP socket at `endpoint`: the original naogateway's robots. */
    final case class ZeroMq(endpoint: String) extends Transport
  }

  /** What can be sent to a robot. */
  sealed trait Outbound extends Product with Serializable

  /** The kinds of outbound traffic. */
  object Outbound {

    /** An RPC call (with its call id set). */
    final case class CallOut(call: RpcCall) extends Outbound

    /** Debug option management. */
    final case class DebugOut(commands: DebuggingCommands) extends Outbound

    /** A ready secure-stream segment. */
    final case class SegmentOut(bytes: Array[Byte]) extends Outbound
  }

  /** The robot's children, for callers that talk to it directly. */
  final case class Connected(
      robotId: Int,
      response: ActorRef[ResponseActor.Command],
      noResponse: ActorRef[NoResponseActor.Command],
      vision: ActorRef[VisionActor.Command],
      stream: ActorRef[StreamActor.Command]
  )

  private final case class Children(
      heartbeat: ActorRef[HeartBeatActor.Command],
      response: ActorRef[ResponseActor.Command],
      noResponse: ActorRef[NoResponseActor.Command],
      vision: ActorRef[VisionActor.Command],
      stream: ActorRef[StreamActor.Command]
  ) {
    def connected(robotId: Int): Connected = Connected(robotId, response, noResponse, vision, stream)
  }

  /** Events a robot actor holds while it waits for the gateway's subscriber list. */
  private val HeldEvents = 64

  /**
   * A robot actor for `robotId` at `address`; `heard` says whether it has spoken already (online at once).
   * `transport` says how it is reached; everything above the transport is the same for both kinds. A `discovered`
   * robot (introduced by its own keep-alive, `naogateway.discovery`) is not online from that one keep-alive: a second
   * one or a probe's answer brings it online, and it stops itself (publishing [[RobotForgotten]]) when it has not come
   * online within `discovery.forget-unreached-after` or stayed offline for `discovery.forget-offline-after`.
   */
  def apply(
      robotId: Int,
      address: InetSocketAddress,
      settings: GatewaySettings,
      outbox: ActorRef[Outbox.Command],
      wiring: Wiring,
      heard: Boolean,
      transport: Transport = Transport.Datagrams,
      discovered: Boolean = false
  ): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        Behaviors.withStash(64) { stash =>
          // Datagrams handed to an earlier incarnation are gone with it; the count starts again.
          wiring.backlog.reset()
          wiring.gateway.foreach(_ ! SubscribersWanted(context.self))
          new Robot(robotId, settings, outbox, wiring, transport, discovered, context, stash, timers).start(address, heard)
        }
      }
    }

  private final class Robot(
      robotId: Int,
      settings: GatewaySettings,
      outbox: ActorRef[Outbox.Command],
      wiring: Wiring,
      transport: Transport,
      discovered: Boolean,
      context: ActorContext[Command],
      stash: StashBuffer[Command],
      timers: TimerScheduler[Command]
  ) {
    private val heartbeatReports = context.messageAdapter[HeartBeatActor.Report](HeartbeatReport.apply)
    private val heartbeatSettings = transport match {
      case Transport.Datagrams => settings.heartbeat
      case _: Transport.ZeroMq => settings.zeromq.heartbeat
    }
    private var zeroMqLink: Option[ActorRef[ZeroMqRobotLink.Command]] = None
    // Frames to a robot that must sign are signed by the outbox as they leave (secure-stream segments never are).
    private val signs = transport == Transport.Datagrams && settings.signingOf(robotId) == RobotSigning.Required
    // Set by the gateway (Subscribers); None until its first answer, and events wait meanwhile.
    private var subscribers: Option[Set[ActorRef[GatewayEvent]]] = if (wiring.gateway.isDefined) None else Some(wiring.subscribers)
    private var held = Vector.empty[GatewayEvent]

    // Link figures: mutable counters owned by this actor alone.
    private var address: InetSocketAddress = null
    private var form: HeaderForm = HeaderForm.Legacy
    private var datagramsIn, datagramsOut, bytesIn, bytesOut, retransmissions = 0L
    private var rejected = Map.empty[Rejection, Long]
    private var rttNanos: Option[Double] = None
    // Oldest first, trimmed to the quality window, and never more than lossEstimate can tell apart: with more than a
    // window's worth of keep-alives the estimate is 0 anyway, so a flooding robot costs what a punctual one costs.
    private val keepAliveTimes = scala.collection.mutable.ArrayDeque.empty[Long]
    private val keepAliveTimesKept = (heartbeatSettings.qualityWindow / heartbeatSettings.keepAliveInterval).toInt + 2
    private def trimKeepAliveTimes(before: Long): Unit =
      while (keepAliveTimes.nonEmpty && keepAliveTimes.head < before) keepAliveTimes.removeHead()
    // The latest keep-alive's fields, the address and the link quality; `online` is not kept here but taken from the
    // behaviour (unreached, or running with its flag) whenever the snapshot leaves this actor (`view`).
    private var snapshot: RobotSnapshot = null
    // The restart rule's state: the session believed in and a candidate new one (KeepAliveStep.keepAlive).
    private var sessions = SessionRule.empty
    // A discovered robot's first keep-alive (the one that introduced it) does not make it online: anyone can send one.
    private var introducing = discovered
    // The robot's clock against the gateway's, from keep-alives alone; a new session at every restart.
    private var clockSync = ClockSync(settings.clockSync)
    // Debug options switched on through the gateway, re-enabled after a robot restart.
    private var activeOptions = Set.empty[String]
    // The robot's option list of this session (protocol.md 8): None until its optionPush answers our optionPull.
    // Over datagrams, option commands wait for it; a ZeroMQ robot is not pulled (docs/zeromq.md).
    private var optionList: Option[Seq[DebuggingOption]] = None
    private var pulling = false
    // The camera streams of this robot and whether each wants grid frames: kept here, so a restarted vision actor
    // gets them back (VisionSubscribersWanted). Apps subscribe through the middleware, one stream each.
    private var visionSubscribers = Map.empty[ActorRef[VisionFrame], Boolean]
    // How every child is restarted (naogateway.supervision.robot-children).
    private val childRestarts = settings.supervision.robotChildren.strategy

    def start(at: InetSocketAddress, heard: Boolean): Behavior[Command] = {
      address = at
      snapshot = RobotSnapshot(robotId, at)
      transport match {
        case Transport.ZeroMq(endpoint) =>
          val loop = ZeroMqRobotLink.SharedLoop(context.system).loop
          zeroMqLink = Some(context.spawn(
            Behaviors.supervise(ZeroMqRobotLink(robotId, endpoint, settings.zeromq, settings.competition,
              context.messageAdapter(ZeroMqLinkEvent.apply), loop)).onFailure(childRestarts),
            "zeromq-link"
          ))
        case Transport.Datagrams => ()
      }
      val heartbeat = context.spawn(
        Behaviors.supervise(HeartBeatActor(heartbeatSettings, heartbeatReports, online = false)).onFailure(childRestarts),
        "heartbeat",
        Gateway.RobotDispatcher
      )
      if (heard) heartbeat ! HeartBeatActor.KeepAliveSeen
      forgetAfter(settings.discovery.forgetUnreachedAfter, "not online")
      unreached(heartbeat)
    }

    private def spawnChildren(heartbeat: ActorRef[HeartBeatActor.Command]): Children = {
      val self = context.self
      val response =
        context.spawn(Behaviors.supervise(ResponseActor(robotId, settings.calls, self, online = true)).onFailure(childRestarts), "response", Gateway.RobotDispatcher)
      Children(
        heartbeat,
        response,
        context.spawn(Behaviors.supervise(NoResponseActor(robotId, settings.calls, response)).onFailure(childRestarts), "no-response", Gateway.RobotDispatcher),
        context.spawn(Behaviors.supervise(VisionActor(robotId, self)).onFailure(childRestarts), "vision", Gateway.RobotDispatcher),
        context.spawn(Behaviors.supervise(StreamActor(robotId, settings.stream, self)).onFailure(childRestarts), "stream", Gateway.RobotDispatcher)
      )
    }

    /** Not reached yet: Connect waits (stashed) until the heartbeat says the robot is there. */
    private def unreached(heartbeat: ActorRef[HeartBeatActor.Command]): Behavior[Command] = Behaviors.receiveMessage {
      case HeartbeatReport(HeartBeatActor.CameOnline) =>
        val children = spawnChildren(heartbeat)
        wentOnline()
        stash.unstashAll(running(children, online = true))
      case c: Connect =>
        if (stash.isFull) context.log.warn("Robot [{}]: too many connects waiting", robotId) else stash.stash(c)
        heartbeat ! HeartBeatActor.ProbeNow
        Behaviors.same
      case Wanted =>
        heartbeat ! HeartBeatActor.ProbeNow
        Behaviors.same
      case other => common(other, None, heartbeat, online = false)
    }

    private def running(children: Children, online: Boolean): Behavior[Command] = Behaviors.receiveMessage {
      case Connect(replyTo) =>
        replyTo ! children.connected(robotId)
        if (!online) children.heartbeat ! HeartBeatActor.ProbeNow
        Behaviors.same
      case Wanted =>
        if (!online) children.heartbeat ! HeartBeatActor.ProbeNow
        Behaviors.same
      case HeartbeatReport(HeartBeatActor.CameOnline) =>
        if (!online) {
          // Children first: a subscriber that calls the moment it hears RobotOnline must find them online.
          children.response ! ResponseActor.Reachability(true)
          wentOnline()
        }
        running(children, online = true)
      case HeartbeatReport(HeartBeatActor.WentOffline(reason)) =>
        context.log.info("Robot [{}] offline: {}", robotId, reason)
        forgetAfter(settings.discovery.forgetOfflineAfter, "offline")
        children.response ! ResponseActor.Reachability(false)
        publish(RobotOffline(robotId, reason))
        running(children, online = false)
      case other => common(other, Some(children), children.heartbeat, online)
    }

    /** Called as the behaviour becomes online: the quality starts good (HeartBeatActor's rule), options are pulled. */
    private def wentOnline(): Unit = {
      timers.cancel(ForgetKey)
      context.log.info("Robot [{}] online at {}", robotId, address)
      snapshot = snapshot.copy(quality = LinkQuality.Good)
      if (pullsOptions && optionList.isEmpty) { if (pulling) sendPull(online = true) else startPull(online = true) }
      publish(RobotOnline(robotId, address))
    }

    /** A discovered robot is forgotten when it is still not online after `delay`; configured robots never are. */
    private def forgetAfter(delay: FiniteDuration, state: String): Unit =
      if (discovered) timers.startSingleTimer(ForgetKey, Forget(s"$state for ${delay.toSeconds} s"), delay)

    private def publish(event: GatewayEvent): Unit = subscribers match {
      case Some(all) => all.foreach(_ ! event)
      // The gateway answers within one of its messages; a bound all the same, so a silent gateway costs no memory.
      case None => if (held.size < HeldEvents) held :+= event
    }

    /** The snapshot as it leaves this actor: `online` from the behaviour, the quality offline while offline. */
    private def view(online: Boolean): RobotSnapshot =
      snapshot.copy(online = online, quality = if (online) snapshot.quality else LinkQuality.Offline)

    private def pullsOptions: Boolean = transport == Transport.Datagrams

    /** protocol.md 8, step 1: `optionPull` now and about every second until an `optionPush` arrives. */
    private def startPull(online: Boolean): Unit =
      if (pullsOptions) {
        pulling = true
        optionList = None
        sendPull(online)
        timers.startTimerWithFixedDelay(PullKey, PullOptions, OptionPullInterval)
      }

    private def sendPull(online: Boolean): Unit =
      // Not while the robot is offline: it would only fill a silent robot's buffer.
      if (online)
        context.self ! Transmit(Outbound.DebugOut(DebuggingCommands(optionPull = Some(true))), Priority.Debug, None)

    /** The robot's list arrived (steps 2, 3); the first one of a session lets the options we want go out (step 4). */
    private def optionsPushed(list: Seq[DebuggingOption]): Unit = {
      optionList = Some(list)
      if (pulling) {
        pulling = false
        timers.cancel(PullKey)
        val offered = list.map(_.name)
        val (known, unknown) = activeOptions.toVector.sorted
          .partition(n => offered.exists(o => o == n || o.startsWith(n + ".")))
        if (unknown.nonEmpty) context.log.info("Robot [{}] does not offer options {}", robotId, unknown.mkString(","))
        if (known.nonEmpty)
          context.self ! Transmit(Outbound.DebugOut(DebuggingCommands(optionEnable = Some(DebuggingOptionNames(known)))),
            Priority.Debug, None)
      }
    }

    /** Messages handled the same way in every state. */
    private def common(
        message: Command,
        children: Option[Children],
        heartbeat: ActorRef[HeartBeatActor.Command],
        online: Boolean
    ): Behavior[Command] = message match {
      case FrameReceived(contents, frameForm, size) =>
        wiring.backlog.done()
        frame(contents, frameForm, size, children, heartbeat, online)
        Behaviors.same
      case SegmentReceived(bytes) =>
        wiring.backlog.done()
        datagramsIn += 1
        bytesIn += bytes.length
        children.foreach(_.stream ! StreamActor.SegmentReceived(bytes))
        Behaviors.same
      case DatagramRejected(kind) =>
        wiring.backlog.done()
        // The gateway warned of it already (per kind, for all robots): here it is counted, and logged at debug only, so
        // robots that come and go cannot multiply the warnings.
        count(kind, warn = false)
        Behaviors.same
      case Subscribers(now) =>
        subscribers = Some(now)
        held.foreach(e => now.foreach(_ ! e))
        held = Vector.empty
        Behaviors.same
      case ReachabilityWanted(replyTo) =>
        replyTo ! online
        Behaviors.same
      case VisionSubscribe(subscriber, grid) =>
        if (!visionSubscribers.contains(subscriber)) context.watchWith(subscriber, VisionSubscriberGone(subscriber))
        visionSubscribers = visionSubscribers.updated(subscriber, grid)
        children.foreach(_.vision ! VisionActor.Subscribers(visionSubscribers))
        Behaviors.same
      case VisionSubscriberGone(subscriber) =>
        visionSubscribers -= subscriber
        children.foreach(_.vision ! VisionActor.Subscribers(visionSubscribers))
        Behaviors.same
      case VisionSubscribersWanted(replyTo) =>
        replyTo ! VisionActor.Subscribers(visionSubscribers)
        Behaviors.same
      case Forget(reason) =>
        // The gateway watches this actor: its IP address and id are free once it has stopped.
        context.log.info("Robot [{}] forgotten: {}", robotId, reason)
        publish(RobotForgotten(robotId, reason))
        Behaviors.stopped
      case Rebound(newAddress) =>
        context.log.info("Robot [{}] re-bound from {} to {}", robotId, address, newAddress)
        address = newAddress
        snapshot = snapshot.copy(address = newAddress)
        routeChanged(children)
        Behaviors.same
      case RouteWanted(replyTo) =>
        replyTo ! ResponseActor.RouteChanged(route)
        Behaviors.same
      case SentDirect(bytes) =>
        datagramsOut += 1
        bytesOut += bytes
        Behaviors.same
      case PullOptions =>
        sendPull(online)
        Behaviors.same
      case Transmit(Outbound.DebugOut(commands), _, outcome, tag) if pulling && commands.optionPull.isEmpty =>
        // Step 4 waits for the list: remembered now, sent (as far as the robot offers it) when the push arrives.
        noteOptions(commands)
        outcome.foreach(_ ! Outbox.Accepted(tag))
        Behaviors.same
      case Transmit(out, priority, outcome, tag) =>
        transmit(out, priority, outcome, tag)
        Behaviors.same
      case GameStateChanged(reading) =>
        zeroMqLink.foreach(_ ! ZeroMqRobotLink.GameStateChanged(reading))
        Behaviors.same
      case ZeroMqLinkEvent(ZeroMqRobotLink.MessageReceived(contents, size)) =>
        frame(contents, HeaderForm.Legacy, size, children, heartbeat, online)
        Behaviors.same
      case ZeroMqLinkEvent(ZeroMqRobotLink.MessageRejected(reason)) =>
        count(Rejection.BadProtobuf, reason)
        Behaviors.same
      case RoundTrip(nanos) =>
        rttNanos = Some(rttNanos.fold(nanos.toDouble)(r => r * 0.875 + nanos * 0.125))
        Behaviors.same
      case Retransmitted =>
        retransmissions += 1
        Behaviors.same
      case HeartbeatReport(HeartBeatActor.SendProbe(call)) =>
        context.self ! Transmit(Outbound.CallOut(call), Priority.Heartbeat, None)
        Behaviors.same
      case HeartbeatReport(HeartBeatActor.ProbeRoundTrip(nanos)) =>
        context.self ! RoundTrip(nanos)
        Behaviors.same
      case HeartbeatReport(HeartBeatActor.QualityChanged(quality)) =>
        context.log.info("Robot [{}] link quality {}", robotId, quality.name)
        snapshot = snapshot.copy(quality = quality)
        publish(LinkQualityChanged(robotId, quality))
        Behaviors.same
      case GetSnapshot(replyTo) =>
        replyTo ! view(online)
        Behaviors.same
      case GetLinkStats(replyTo) =>
        replyTo ! LinkStats(robotId, datagramsIn, datagramsOut, bytesIn, bytesOut, rttNanos.map(_ / 1e6), lossEstimate(),
          retransmissions, rejected.map { case (k, n) => k.name -> n }, clockSync.estimate)
        Behaviors.same
      case HeartbeatReport(HeartBeatActor.CameOnline | HeartBeatActor.WentOffline(_)) | Connect(_) | Wanted =>
        Behaviors.unhandled
    }

    /** Where calls go now: this actor owns the address and header form, the response actor follows them. */
    private def route: ResponseActor.Route =
      zeroMqLink.fold[ResponseActor.Route](ResponseActor.Route.Datagrams(outbox, address, form, signs))(ResponseActor.Route.ZeroMq(_))

    private def routeChanged(children: Option[Children]): Unit =
      children.foreach(_.response ! ResponseActor.RouteChanged(route))

    /** One FU-Remote message from the robot, over datagrams or ZeroMQ. */
    private def frame(
        contents: MessageContents,
        frameForm: HeaderForm,
        size: Int,
        children: Option[Children],
        heartbeat: ActorRef[HeartBeatActor.Command],
        online: Boolean
    ): Unit = {
      datagramsIn += 1
      bytesIn += size
      if (frameForm != form) {
        form = frameForm
        routeChanged(children)
      }
      contents.status.foreach(_ => keepAlive(contents, children, heartbeat, online))
      contents.debuggingCommands.flatMap(_.optionPush).foreach(list => optionsPushed(list.options))
      contents.rpcResponse.foreach { response =>
        val reply = RpcReply.fromProto(response)
        reply.callId.foreach { id =>
          CallId.ownerOf(id) match {
            case Some(CallId.Owner.Response)  => children.foreach(_.response ! ResponseActor.ReplyReceived(reply))
            case Some(CallId.Owner.Heartbeat) => heartbeat ! HeartBeatActor.ProbeAnswered(id)
            case _                            => count(Rejection.UnknownCallId, s"call id $id")
          }
        }
      }
      contents.havimoRegions.foreach { f =>
        HaViMo.decodeRegions(f.records.map(_.toByteArray).getOrElse(Array.emptyByteArray)) match {
          case Right(regions) =>
            children.foreach(_.vision ! VisionActor.FrameReceived(
              VisionFrame.Regions(robotId, f.frame & 0xffffffffL, f.timestamp, regions)))
          case Left(e) => count(Rejection.BadHaViMo, e.describe)
        }
      }
      contents.havimoGrid.foreach { f =>
        HaViMo.decodeGrid(f.cells.toByteArray) match {
          case Right(grid) =>
            children.foreach(_.vision ! VisionActor.FrameReceived(VisionFrame.Grid(robotId, f.frame & 0xffffffffL, f.timestamp, grid)))
          case Left(e) => count(Rejection.BadHaViMo, e.describe)
        }
      }
    }

    /** Encodes `out` for this robot's transport and hands it on: to the outbox, or to the ZeroMQ link. */
    private def transmit(out: Outbound, priority: Priority, outcome: Option[ActorRef[Outbox.Outcome]], tag: Long): Unit =
      zeroMqLink match {
        case None =>
          encode(out) match {
            case Right(bytes) =>
              datagramsOut += 1
              bytesOut += bytes.length
              val signed = signs && (out match {
                case _: Outbound.SegmentOut => false
                case _                      => true
              })
              outbox ! Outbox.Send(robotId, address, bytes, priority, outcome, tag, signed)
            case Left(error) =>
              outcome.foreach(_ ! Outbox.Dropped(tag, error.describe))
          }
        case Some(link) =>
          // No FU-Remote header over ZeroMQ: a ZeroMQ message carries exactly one serialized Message.
          contentsOf(out) match {
            case Some(contents) =>
              val bytes = contents.toProtobuf
              datagramsOut += 1
              bytesOut += bytes.length
              link ! ZeroMqRobotLink.Send(bytes, outcome, tag)
            case None => outcome.foreach(_ ! Outbox.Dropped(tag, "the secure stream does not run over ZeroMQ"))
          }
      }

    private def count(kind: Rejection, detail: => String = "", warn: Boolean = true): Unit = {
      val n = rejected.getOrElse(kind, 0L) + 1
      rejected = rejected.updated(kind, n)
      // Per kind, at 1, 10, 100, ...: the kinds are a closed set, so neither the map nor the log can grow with a flood.
      if (warn && RateLimitedLog.due(n)) context.log.warn("Robot [{}]: refused datagram ({}), {} so far", robotId, kind.name, n)
      if (context.log.isDebugEnabled) context.log.debug("Robot [{}]: refused datagram ({}) {}", robotId, kind.name, detail)
    }

    private def lossEstimate(): Double = {
      val now = System.nanoTime()
      val window = heartbeatSettings.qualityWindow.toNanos
      trimKeepAliveTimes(now - window)
      // Over the window, or over the time since the first keep-alive when the robot is younger than that.
      val observed = keepAliveTimes.headOption.fold(window)(first => math.min(window, now - first + heartbeatSettings.keepAliveInterval.toNanos))
      val expected = observed.toDouble / heartbeatSettings.keepAliveInterval.toNanos
      if (datagramsIn == 0) 1.0 else math.max(0.0, 1.0 - keepAliveTimes.size / expected)
    }

    private def keepAlive(
        contents: MessageContents,
        children: Option[Children],
        heartbeat: ActorRef[HeartBeatActor.Command],
        online: Boolean
    ): Unit = {
      if (introducing) introducing = false else heartbeat ! HeartBeatActor.KeepAliveSeen
      val now = System.nanoTime()
      // Only the quality window's worth is kept (25 at the defaults), trimmed on every keep-alive.
      if (keepAliveTimes.size >= keepAliveTimesKept) keepAliveTimes.removeHead()
      keepAliveTimes.append(now)
      trimKeepAliveTimes(now - settings.heartbeat.qualityWindow.toNanos)
      val step = KeepAliveStep.keepAlive(snapshot, sessions, contents.status.get, contents.robotHealth, now, settings.newSessionKeepAlives)
      sessions = step.sessions
      if (step.restarted) clockSync = clockSync.restart
      // Status.timestamp is the robot's clock (64 bits); RobotHealth.uptimeMs (32 bits) only stands in for it.
      val robotTime = contents.status.get.timestamp
        .orElse(contents.robotHealth.flatMap(_.uptimeMs).map(u => clockSync.unwrap32(u.toLong)))
      robotTime.foreach(t => clockSync = clockSync.add(t, now))
      val clock = clockSync.estimate
      snapshot = step.snapshot.copy(clock = clock, stampedAtNanos = for (t <- robotTime; c <- clock) yield c.toGatewayNanos(t))
      if (step.restarted) resync(children, online)
      publish(RobotStatusUpdated(view(online)))
    }

    /** A fresh session on the robot: switch back on what was active, and tell subscribers. */
    private def resync(children: Option[Children], online: Boolean): Unit = {
      context.log.info("Robot [{}] restarted (boot {}); re-enabling {}", robotId, snapshot.bootId, activeOptions.mkString(","))
      val options = activeOptions.toVector.sorted
      // A new session: pull its option list first (protocol.md 8, steps 1 and 6); the push re-enables `options`.
      if (pullsOptions) startPull(online)
      else if (options.nonEmpty)
        context.self ! Transmit(Outbound.DebugOut(DebuggingCommands(optionEnable = Some(DebuggingOptionNames(options)))),
          Priority.Debug, None)
      children.foreach { c =>
        c.vision ! VisionActor.Resync
        c.stream ! StreamActor.Reset
      }
      publish(RobotRestarted(robotId, snapshot.bootId, options))
    }

    private def contentsOf(out: Outbound): Option[MessageContents] = out match {
      case Outbound.CallOut(call) => Some(MessageContents(robotId, rpcRequest = Some(call.toProto)))
      case Outbound.DebugOut(commands) =>
        noteOptions(commands)
        Some(MessageContents(robotId, debuggingCommands = Some(commands)))
      case Outbound.SegmentOut(_) => None
    }

    private def noteOptions(commands: DebuggingCommands): Unit = {
      commands.optionEnable.foreach(e => activeOptions ++= e.options)
      commands.optionDisable.foreach(d => activeOptions = activeOptions.filterNot(o => d.options.exists(n => o == n || o.startsWith(n + "."))))
    }

    private def encode(out: Outbound): Either[FrameError, Array[Byte]] = out match {
      case Outbound.CallOut(call) =>
        MessageContents.encodeFrame(MessageContents(robotId, rpcRequest = Some(call.toProto)), form)
      case Outbound.DebugOut(commands) =>
        noteOptions(commands)
        MessageContents.encodeFrame(MessageContents(robotId, debuggingCommands = Some(commands)), form)
      case Outbound.SegmentOut(bytes) =>
        if (bytes.length > WireLimits.MaxDatagramBytes) Left(FrameError.Oversize(bytes.length, WireLimits.MaxDatagramBytes))
        else Right(bytes)
    }
  }
}
