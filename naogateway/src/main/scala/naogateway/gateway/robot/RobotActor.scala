package naogateway.gateway.robot

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.actor.typed.scaladsl.Behaviors.receiveMessage
import akka.actor.typed.scaladsl.{ActorContext, Behaviors, StashBuffer, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior}

import naogateway.gateway.robot.RobotEffects.{Children, Connected, Family}
import naogateway.gateway.link.ZeroMqRobotLink
import naogateway.proto.DebuggingCommands
import naogateway.wire._
import naogateway.access.RobotAccess
import naogateway.api.{GatewayEvent, RobotForgotten, RobotOffline, RobotOnline, VisionFrame}
import naogateway.gateway.{Gateway, GatewaySettings, Rejection, RobotSigning}

/** The supervisor of one robot: carries out `RobotState`'s transitions (its address, liveness, subscribers, options and
  * link figures), hands what the robot sends to its owners, and re-syncs the robot after restarts. It sends nothing
  * itself: everything for the robot goes through its child `NoResponseActor`, the robot's one sender. The middleware
  * reaches it through [[RobotAccess]], whose messages it wraps into its own as they arrive ([[RobotRef]]).
  */
object RobotActor {

  /** What a robot actor takes from the gateway and its own children, and the middleware's messages wrapped. */
  private[naogateway] sealed trait Command

  /** What a robot actor handles alike in every state (the rest: Connect, the heartbeat's verdicts, Forget). */
  private[naogateway] sealed trait Common extends Command

  /** A decoded FU-Remote frame from this robot (`size` bytes on the wire). */
  private[naogateway] final case class FrameReceived(contents: MessageContents, form: HeaderForm, size: Int)
      extends Common

  /** A secure-stream segment from this robot's address. */
  private[naogateway] final case class SegmentReceived(bytes: Array[Byte]) extends Common

  /** A datagram from this robot's address was refused, for this kind of reason. */
  private[naogateway] final case class DatagramRejected(kind: Rejection) extends Common

  /** The robot was re-bound to another IP address (it moved host); `address` is where it receives now. */
  private[naogateway] final case class Rebound(address: InetSocketAddress) extends Common

  /** Asks for the children of a reachable robot: waits (stashed) while it is not reached, probing it. */
  private[naogateway] sealed trait Reach extends Command {
    private[naogateway] def answer(children: Connected): Unit
  }

  /** Answers with the children's refs once the robot is reachable (the gateway's own specs, through its test kit). */
  private[naogateway] final case class Connect(replyTo: ActorRef[Connected]) extends Reach {
    private[naogateway] def answer(children: Connected): Unit = replyTo ! children
  }

  /** The middleware's [[RobotAccess.Open]]: waits like `Connect`, and answers with the children it may use. */
  private[naogateway] final case class Opening(open: RobotAccess.Open) extends Reach {
    private[naogateway] def answer(c: Connected): Unit =
      open.replyTo ! RobotAccess.Opened(c.robotId, c.response, c.registrations)
  }

  /** The middleware's questions, answered alike in every state. */
  private[naogateway] final case class Asked(question: RobotAccess.Question) extends Common

  /** The gateway's event subscribers now: this robot's events go to them directly, not through the gateway; those in
    * `statusless` (the recorder, which reads the status off the tap) get no `RobotStatusUpdated`.
    */
  private[naogateway] final case class Subscribers(subscribers: Set[ActorRef[GatewayEvent]],
      statusless: Set[ActorRef[GatewayEvent]] = Set.empty)
      extends Common

  /** A robot actor (re)started and asks the gateway for its current subscribers. */
  private[naogateway] final case class SubscribersWanted(robot: ActorRef[Subscribers])

  /** Messages from the robot's own children: only they hold the robot actor's ref as this type. */
  private[naogateway] sealed trait FromChild extends Common

  /** A caller wants the robot while it is offline: probe it now. */
  private[naogateway] case object Wanted extends FromChild

  /** A clean round-trip sample. */
  private[naogateway] final case class RoundTrip(nanos: Long) extends FromChild

  /** A call was sent again. */
  private[naogateway] case object Retransmitted extends FromChild

  /** The sender (re)started and asks for the robot's route; every later change is pushed to it. */
  private[naogateway] final case class RouteWanted(replyTo: ActorRef[NoResponseActor.Command]) extends FromChild

  /** A debug option command (the vision actor's): noted here, so a robot restart can re-enable it, then sent. */
  private[naogateway] final case class OptionCommand(commands: DebuggingCommands) extends FromChild

  /** A call actor (re)started and asks whether the robot is reachable now; a restart must not forget it is offline. */
  private[naogateway] final case class ReachabilityWanted(replyTo: ActorRef[Boolean]) extends FromChild

  /** A stream subscribes to this robot's camera frames (through the vision actor, which this actor outlives). */
  private[naogateway] final case class VisionSubscribe(subscriber: ActorRef[VisionFrame], grid: Boolean)
      extends FromChild

  /** The vision actor (re)started and asks for the registrations; every later change is pushed to it. */
  private[naogateway] final case class VisionSubscribersWanted(replyTo: ActorRef[VisionActor.Subscribers])
      extends FromChild

  private final case class HeartbeatReport(report: HeartBeatActor.Report) extends Common
  private final case class Verdict(report: HeartBeatActor.Verdict) extends Command
  private final case class VisionSubscriberGone(subscriber: ActorRef[VisionFrame]) extends Common
  private final case class ZeroMqLinkEvent(event: ZeroMqRobotLink.Event) extends Common
  private case object PullOptions extends Common
  private case object PullKey
  private final case class Forget(reason: String) extends Command
  private case object ForgetKey

  /** A robot actor for `robotId` at `address`; `heard` says whether it has spoken already (online at once). `transport`
    * says how it is reached; everything above the transport is the same for both kinds. A `discovered` robot
    * (introduced by its own keep-alive, `naogateway.discovery`) is not online from that one keep-alive: a second one or
    * a probe's answer brings it online, and it stops itself (publishing [[RobotForgotten]]) when it has not come online
    * within `discovery.forget-unreached-after` or stayed offline for `discovery.forget-offline-after`.
    */
  private[naogateway] def apply(robotId: Int, address: InetSocketAddress, settings: GatewaySettings,
      outbox: ActorRef[Outbox.Command], wiring: RobotWiring, heard: Boolean,
      transport: RobotTransport = RobotTransport.Datagrams, discovered: Boolean = false): Behavior[Any] =
    Behaviors.setup[Command] { context =>
      Behaviors.withTimers { timers =>
        Behaviors.withStash(64) { stash =>
          // Datagrams handed to an earlier incarnation are gone with it; the count starts again.
          wiring.backlog.reset()
          wiring.gateway.foreach(_ ! SubscribersWanted(context.self))
          val robot = new Robot(robotId, settings, outbox, wiring, transport, discovered, context, stash, timers)
          robot.start(address, heard)
        }
      }
    }.transformMessages[Any] {
      case open: RobotAccess.Open         => Opening(open)
      case question: RobotAccess.Question => Asked(question)
      case own: Command                   => own
    }

  private final class Robot(robotId: Int, settings: GatewaySettings, outbox: ActorRef[Outbox.Command],
      wiring: RobotWiring, transport: RobotTransport, discovered: Boolean, context: ActorContext[Command],
      stash: StashBuffer[Command], timers: TimerScheduler[Command]) {
    private val heartbeatSettings = transport match {
      case RobotTransport.Datagrams => settings.heartbeat
      case _: RobotTransport.ZeroMq => settings.zeromq.heartbeat
    }
    // Frames to a robot that must sign are signed by the outbox as they leave (secure-stream segments never are).
    private val datagrams = transport == RobotTransport.Datagrams
    private val signs = datagrams && settings.signingOf(robotId) == RobotSigning.Required
    private val effects = new RobotEffects(
      robotId,
      settings,
      heartbeatSettings,
      datagrams,
      wiring.clocks.slot(robotId),
      context.log,
      timers.startTimerWithFixedDelay(PullKey, PullOptions, RobotOptions.PullInterval),
      timers.cancel(PullKey)
    )
    // How every child is restarted (naogateway.supervision.robot-children).
    private val restarts = settings.supervision.robotChildren.strategy
    // What the sender sends, counted by it as it goes; read here for the link figures.
    private val sent = new SentFigures
    private def child[T](behavior: Behavior[T], name: String): ActorRef[T] =
      context.spawn(Behaviors.supervise(behavior).onFailure(restarts), name, Gateway.RobotDispatcher)

    def start(at: InetSocketAddress, heard: Boolean): Behavior[Command] = {
      // The sender first: the heartbeat's probes, the link's polls and the stream's segments go to it directly.
      val sender = child(NoResponseActor(robotId, settings.calls, context.self, sent), "no-response")
      val zeroMq = transport match {
        case RobotTransport.ZeroMq(endpoint) =>
          val loop = ZeroMqRobotLink.SharedLoop(context.system).loop
          Some(context.spawn(
              Behaviors.supervise(ZeroMqRobotLink(robotId, endpoint, settings.zeromq,
                  context.messageAdapter(ZeroMqLinkEvent.apply), sender, loop)).onFailure(restarts),
              "zeromq-link"
            ))
        case RobotTransport.Datagrams => None
      }
      val reports = context.messageAdapter[HeartBeatActor.Report] {
        case v: HeartBeatActor.Verdict => Verdict(v)
        case r                         => HeartbeatReport(r)
      }
      val keepAlives = new HeartBeatActor.KeepAlives
      val heartbeat =
        child(HeartBeatActor(heartbeatSettings, reports, sender, online = false, keepAlives, wiring.port), "heartbeat")
      val response = child(ResponseActor(robotId, settings.calls, context.self, sender, online = false), "response")
      if (heard && keepAlives.seen(System.nanoTime())) heartbeat ! HeartBeatActor.KeepAliveSeen
      forgetAfter(settings.discovery.forgetUnreachedAfter, "not online")
      val kept = (heartbeatSettings.qualityWindow / heartbeatSettings.keepAliveInterval).toInt + 2
      val subscribers = if (wiring.gateway.isDefined) None else Some(wiring.subscribers)
      unreached(Family(heartbeat, keepAlives, sender, response, zeroMq),
        RobotState.initial(robotId, at, ClockSync(settings.clockSync), subscribers, discovered, kept, signs))
    }

    // Each state holds its current RobotState in a local `s`, replaced by the state's pure transitions, and answers
    // what changes only `s` with `Behaviors.same`: a new behaviour per message would re-wrap every interceptor around
    // the actor (its timers, its message adapter, its supervision), which cost an ingest blast about a tenth of the
    // port loop's allocations (profiled).
    /** Not reached yet: Connect waits (stashed) until the heartbeat says the robot is there. */
    private def unreached(f: Family, s0: RobotState): Behavior[Command] = {
      var s = s0
      receiveMessage {
        case m: Common =>
          s = common(m, f, None, s, isOnline = false)
          Behaviors.same
        case c: Reach =>
          if (stash.isFull) context.log.warn("Robot [{}]: too many connects waiting", robotId) else stash.stash(c)
          f.heartbeat ! HeartBeatActor.ProbeNow
          Behaviors.same
        case Verdict(HeartBeatActor.CameOnline) =>
          val vision = child(VisionActor(robotId, context.self), "vision")
          val stream = child(StreamActor(robotId, settings.stream, f.sender), "stream")
          stash.unstashAll(online(f, Children(vision, stream), s))
        case Verdict(HeartBeatActor.WentOffline(_)) => Behaviors.same // never online: nothing to report
        case Forget(reason)                         => forget(s, reason)
      }
    }

    private def running(f: Family, c: Children, s0: RobotState, isOnline: Boolean): Behavior[Command] = {
      var s = s0
      receiveMessage {
        case m: Common =>
          s = common(m, f, Some(c), s, isOnline)
          Behaviors.same
        case r: Reach =>
          r.answer(Connected(robotId, f.calls, f.sender, c.camera, c.stream))
          if (!isOnline) f.heartbeat ! HeartBeatActor.ProbeNow
          Behaviors.same
        case Verdict(HeartBeatActor.CameOnline) => if (isOnline) Behaviors.same else online(f, c, s)
        case Verdict(HeartBeatActor.WentOffline(reason)) =>
          context.log.info("Robot [{}] offline: {}", robotId, reason)
          forgetAfter(settings.discovery.forgetOfflineAfter, "offline")
          f.response ! ResponseActor.Reachability(false)
          running(f, c, effects.publish(s.wentOffline, RobotOffline(robotId, reason)), isOnline = false)
        case Forget(reason) => forget(s, reason)
      }
    }

    /** The robot came online: the response actor first (a subscriber that calls on RobotOnline must find it online). */
    private def online(f: Family, c: Children, s: RobotState): Behavior[Command] = {
      timers.cancel(ForgetKey)
      context.log.info("Robot [{}] online at {}", robotId, s.address)
      f.response ! ResponseActor.Reachability(true)
      val pulled = effects.pullOnContact(f, s)
      running(f, c, effects.publish(pulled.wentOnline, RobotOnline(robotId, s.address)), isOnline = true)
    }

    /** Everything handled alike in both states: what the robot, the children, the gateway and the timers say. */
    private def common(m: Common, f: Family, c: Option[Children], s: RobotState, isOnline: Boolean): RobotState =
      m match {
        case FrameReceived(contents, form, size) =>
          wiring.backlog.done()
          // Only a verified frame of a robot that must sign gets here (the port's reader checks it first).
          val (next, formChanged) = (if (signs) s.signatureAccepted else s).frameReceived(size, form)
          if (formChanged) f.sender ! NoResponseActor.RouteChanged(route(next, f))
          effects.frame(contents, f, c, next, isOnline)
        case SegmentReceived(bytes) =>
          wiring.backlog.done()
          c.foreach(_.stream ! StreamActor.SegmentReceived(bytes))
          s.segmentReceived(bytes.length)
        case DatagramRejected(kind) =>
          wiring.backlog.done()
          // The gateway warned of it already (per kind, for all robots): here it is counted, and logged at debug only.
          effects.count(s.signatureRefused(kind), kind, "", warn = false)
        case Rebound(to) =>
          context.log.info("Robot [{}] re-bound from {} to {}", robotId, s.address, to)
          val next = s.rebound(to)
          f.sender ! NoResponseActor.RouteChanged(route(next, f))
          next
        case Asked(RobotAccess.GetSnapshot(replyTo))  => replyTo ! s.view(isOnline); s
        case Asked(RobotAccess.GetLinkStats(replyTo)) => replyTo ! effects.linkStats(s, sent); s
        case Subscribers(now, statusless) =>
          val (next, held) = s.subscribersChanged(now, statusless)
          held.foreach(e => next.recipients(e).foreach(_ ! e))
          next
        case Wanted =>
          if (!isOnline) f.heartbeat ! HeartBeatActor.ProbeNow
          s
        case RoundTrip(nanos)            => s.roundTrip(nanos)
        case Retransmitted               => s.retransmitted
        case ReachabilityWanted(replyTo) => replyTo ! isOnline; s
        case RouteWanted(replyTo)        => replyTo ! NoResponseActor.RouteChanged(route(s, f)); s
        case OptionCommand(commands)     => effects.optionCommand(commands, f, s)
        case VisionSubscribe(subscriber, grid) =>
          val (next, fresh) = s.visionSubscribed(subscriber, grid)
          if (fresh) context.watchWith(subscriber, VisionSubscriberGone(subscriber))
          c.foreach(_.vision ! VisionActor.Subscribers(next.vision))
          next
        case VisionSubscribersWanted(replyTo) => replyTo ! VisionActor.Subscribers(s.vision); s
        case VisionSubscriberGone(subscriber) =>
          val next = s.visionGone(subscriber)
          c.foreach(_.vision ! VisionActor.Subscribers(next.vision))
          next
        case PullOptions => effects.pull(f, s, isOnline)
        case ZeroMqLinkEvent(ZeroMqRobotLink.MessageReceived(contents, size)) =>
          effects.frame(contents, f, c, s.frameReceived(size, HeaderForm.Legacy)._1, isOnline)
        case ZeroMqLinkEvent(ZeroMqRobotLink.MessageRejected(reason)) => effects.count(s, Rejection.BadProtobuf, reason)
        case HeartbeatReport(report)                                  => effects.heartbeat(report, s)
      }

    /** Where the robot is reached now: this actor owns the address and header form, the sender follows them. */
    private def route(s: RobotState, f: Family): RobotFrames.Route =
      f.zeroMq.fold[RobotFrames.Route](RobotFrames.Route.Datagrams(outbox, s.address, s.form, signs))(
        RobotFrames.Route.ZeroMq(outbox, s.address, _))

    /** The gateway watches this actor: its IP address and id are free once it has stopped. */
    private def forget(s: RobotState, reason: String): Behavior[Command] = {
      context.log.info("Robot [{}] forgotten: {}", robotId, reason)
      effects.publish(s, RobotForgotten(robotId, reason))
      Behaviors.stopped
    }

    /** A discovered robot is forgotten when it is still not online after `delay`; configured robots never are. */
    private def forgetAfter(delay: FiniteDuration, state: String): Unit =
      if (discovered) timers.startSingleTimer(ForgetKey, Forget(s"$state for ${delay.toSeconds} s"), delay)
  }
}
