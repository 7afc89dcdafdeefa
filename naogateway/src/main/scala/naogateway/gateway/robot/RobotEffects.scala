package naogateway.gateway.robot

import akka.actor.typed.ActorRef

import naogateway.gateway.robot.RobotEffects.{Children, Family}
import naogateway.gateway.robot.RobotFrames.{Arrival, Outbound}
import naogateway.proto.{DebuggingCommands, DebuggingOption, DebuggingOptionNames, RobotHealth, ServoTelemetry, Status}
import naogateway.gateway.link.ZeroMqRobotLink
import naogateway.wire.MessageContents
import naogateway.access.RobotAccess
import naogateway.api.{GatewayEvent, LinkQualityChanged, LinkStats, Priority, RobotRestarted, RobotStatusUpdated}
import naogateway.gateway.{GatewaySettings, HeartbeatSettings, Rejection}
import naogateway.gateway.recording.RobotClockEstimates
import naogateway.transport.RateLimitedLog

/** What a robot actor does around `RobotState`'s transitions: hands what the robot sent to its owners, puts option
  * commands and option pulls into the robot's sender, and publishes events (the heartbeat probes through the sender
  * itself). Its methods take a state and return the next one; it keeps nothing itself. `startPulling` and `stopPulling`
  * run the actor's option-pull timer.
  */
private[naogateway] final class RobotEffects(
    robotId: Int,
    settings: GatewaySettings,
    heartbeatSettings: HeartbeatSettings,
    pullsOptions: Boolean,
    clock: RobotClockEstimates.Slot,
    log: org.slf4j.Logger,
    startPulling: => Unit,
    stopPulling: => Unit
) {
  private val window = heartbeatSettings.qualityWindow.toNanos
  private val interval = heartbeatSettings.keepAliveInterval.toNanos

  /** One FU-Remote message from the robot, over datagrams or ZeroMQ (counted already): each thing to its owner. */
  def frame(contents: MessageContents, f: Family, c: Option[Children], s: RobotState, isOnline: Boolean): RobotState =
    // A keep-alive alone (nearly every frame) goes straight to its handling, with no arrivals built.
    // (A match, not a fold: a fold's function would be built for every frame.)
    if (RobotFrames.keepAliveOnly(contents)) contents.status match {
      case Some(status) => keepAlive(status, contents.robotHealth, contents.servoTelemetry, f, c, s, isOnline)
      case None         => s
    }
    else
      RobotFrames.arrivals(robotId, contents).foldLeft(s) {
        case (st, Arrival.KeepAlive(status, health, servos)) => keepAlive(status, health, servos, f, c, st, isOnline)
        case (st, Arrival.OptionsPushed(list))               => optionsPushed(list, f, st)
        case (st, Arrival.Reply(CallId.Owner.Response, reply, _)) =>
          f.response ! ResponseActor.ReplyReceived(reply)
          st
        case (st, Arrival.Reply(CallId.Owner.Heartbeat, _, id)) =>
          f.heartbeat ! HeartBeatActor.ProbeAnswered(id)
          st
        case (st, Arrival.Reply(owner, _, id)) => count(st, Rejection.UnknownCallId, s"call id $id of $owner")
        case (st, Arrival.Vision(frame)) =>
          c.foreach(_.vision ! VisionActor.FrameReceived(frame))
          st
        case (st, Arrival.Refused(kind, detail)) => count(st, kind, detail)
      }

  /** A keep-alive: the heartbeat hears of it (unless it only introduced the robot), a new session is re-synced. */
  private def keepAlive(status: Status, health: Option[RobotHealth], servos: Option[ServoTelemetry], f: Family,
      c: Option[Children], s0: RobotState, isOnline: Boolean): RobotState = {
    val now = System.nanoTime()
    val (s, seen) = s0.keepAliveSeen(status, health, now, window, settings.newSessionKeepAlives, servos)
    // Counted for the heartbeat, which reads the count on its own timers; told only while it waits for the robot.
    if (seen.heard && f.keepAlives.seen(now)) f.heartbeat ! HeartBeatActor.KeepAliveSeen
    val resynced = if (seen.restarted) resync(f, c, s, isOnline) else s
    // The recorder dates the robot's Status with this estimate, read on its own thread: no event per keep-alive for it.
    clock.update(resynced.snapshot.clock)
    if (resynced.wantsStatus) publish(resynced, RobotStatusUpdated(resynced.view(isOnline))) else resynced
  }

  /** A fresh session on the robot: switch back on what was active, and tell subscribers. */
  private def resync(f: Family, c: Option[Children], s: RobotState, isOnline: Boolean): RobotState = {
    val options = s.options.active.toVector.sorted
    log.info("Robot [{}] restarted (boot {}); re-enabling {}", robotId, s.snapshot.bootId, options.mkString(","))
    // A new session: pull its option list first (protocol.md 8, steps 1 and 6); the push re-enables `options`.
    val pulled = if (pullsOptions) startPull(f, s, isOnline) else s
    if (!pullsOptions && options.nonEmpty)
      submitOptions(f, DebuggingCommands(optionEnable = Some(DebuggingOptionNames(options))))
    c.foreach { ch =>
      ch.vision ! VisionActor.Resync
      ch.stream ! StreamActor.Reset
    }
    publish(pulled, RobotRestarted(robotId, s.snapshot.bootId, options))
  }

  /** The robot came online: a datagram robot's option list is pulled if this session's is still unknown. */
  def pullOnContact(f: Family, s: RobotState): RobotState =
    if (!pullsOptions || s.options.list.nonEmpty) s
    else if (s.options.pulling) pull(f, s, isOnline = true)
    else startPull(f, s, isOnline = true)

  /** protocol.md 8, step 1: `optionPull` now and about every second until an `optionPush` arrives. */
  private def startPull(f: Family, s: RobotState, isOnline: Boolean): RobotState = {
    startPulling
    pull(f, s.pullStarted, isOnline)
  }

  /** One `optionPull`, taking room in the robot's buffer until the push (or the next pull); none while offline. */
  def pull(f: Family, s: RobotState, isOnline: Boolean): RobotState =
    if (!isOnline || !s.options.pulling) s
    else {
      val (next, key) = s.pullSent
      f.sender ! NoResponseActor.Submit(Outbound.DebugOut(DebuggingCommands(optionPull = Some(true))), Priority.Debug,
        Some(key), NoResponseActor.Awaits.Reply(Some(RobotOptions.PullInterval)))
      next
    }

  /** The robot's list arrived (steps 2, 3); the first one of a pull lets the options we want go out (step 4). */
  private def optionsPushed(list: Seq[DebuggingOption], f: Family, s: RobotState): RobotState = {
    f.sender ! NoResponseActor.Finished(s.options.pullKey)
    if (s.options.pulling) stopPulling
    val (next, known, unknown) = s.optionsPushed(list)
    if (unknown.nonEmpty) log.info("Robot [{}] does not offer options {}", robotId, unknown.mkString(","))
    if (known.nonEmpty) submitOptions(f, DebuggingCommands(optionEnable = Some(DebuggingOptionNames(known))))
    next
  }

  /** A child's option command: noted, then sent, unless it waits for the pulled list (step 4). */
  def optionCommand(commands: DebuggingCommands, f: Family, s: RobotState): RobotState = {
    val (next, now) = s.optionCommand(commands)
    if (now) submitOptions(f, commands)
    next
  }

  private def submitOptions(f: Family, commands: DebuggingCommands): Unit =
    f.sender ! NoResponseActor.Submit(Outbound.DebugOut(commands), Priority.Debug, None, NoResponseActor.Awaits.Nothing)

  /** What the heartbeat reports besides its verdicts: a round trip, the link quality. */
  def heartbeat(report: HeartBeatActor.Report, s: RobotState): RobotState = report match {
    case HeartBeatActor.ProbeRoundTrip(nanos) => s.roundTrip(nanos)
    case HeartBeatActor.QualityChanged(quality) =>
      log.info("Robot [{}] link quality {}", robotId, quality.name)
      publish(s.qualityChanged(quality), LinkQualityChanged(robotId, quality))
    case _: HeartBeatActor.Verdict => s // the robot actor's states decide on those
  }

  /** The link figures now, with what the sender counted as it sent. */
  def linkStats(s: RobotState, out: SentFigures): LinkStats = s.linkStats(System.nanoTime(), window, interval, out)

  /** A refused datagram of `kind`: counted, and warned of at 1, 10, 100, ... per kind. */
  def count(s: RobotState, kind: Rejection, detail: => String, warn: Boolean = true): RobotState = {
    val (next, n) = s.refused(kind)
    // The kinds are a closed set, so neither the map nor the log can grow with a flood.
    if (warn && RateLimitedLog.due(n)) log.warn("Robot [{}]: refused datagram ({}), {} so far", robotId, kind.name, n)
    if (log.isDebugEnabled) log.debug("Robot [{}]: refused datagram ({}) {}", robotId, kind.name, detail)
    next
  }

  /** Publishes `event` to the subscribers, or holds it until the gateway has named them. */
  def publish(s: RobotState, event: GatewayEvent): RobotState = {
    val (next, to) = s.publish(event)
    to.foreach(_ ! event)
    next
  }
}

/** The robot actor's children, as its effects reach them: each one held once, an actor spawned for two protocols (its
  * own and the middleware's, wrapped as they arrive) seen through both by its two views.
  */
private[naogateway] object RobotEffects {

  /** The children that live as long as the robot actor (the vision and stream actors come with the first contact);
    * `responder` is the response actor, `keepAlives` what the robot actor counts for the heartbeat.
    */
  final case class Family(
      heartbeat: ActorRef[HeartBeatActor.Command],
      keepAlives: HeartBeatActor.KeepAlives,
      sender: ActorRef[NoResponseActor.Command],
      responder: ActorRef[Any],
      zeroMq: Option[ActorRef[ZeroMqRobotLink.Command]]
  ) {

    /** The response actor as the robot's actors reach it. */
    def response: ActorRef[ResponseActor.Command] = responder

    /** The response actor as callers reach it. */
    def calls: ActorRef[RobotAccess.Call] = responder
  }

  /** The robot's children as the gateway's own specs reach them (`RobotActor.Connect`); `response` and `registrations`
    * as in [[RobotAccess.Opened]].
    */
  final case class Connected(robotId: Int, response: ActorRef[RobotAccess.Call],
      noResponse: ActorRef[NoResponseActor.Command], camera: ActorRef[Any], stream: ActorRef[StreamActor.Command]) {

    /** The vision actor as the robot actor reaches it. */
    def vision: ActorRef[VisionActor.Command] = camera

    /** The vision actor as subscribers reach it. */
    def registrations: ActorRef[RobotAccess.RegisterVision] = camera
  }

  /** The children spawned at first contact; `camera` is the vision actor. */
  final case class Children(camera: ActorRef[Any], stream: ActorRef[StreamActor.Command]) {

    /** The vision actor as the robot actor reaches it. */
    def vision: ActorRef[VisionActor.Command] = camera

    /** The vision actor as subscribers reach it. */
    def registrations: ActorRef[RobotAccess.RegisterVision] = camera
  }
}
