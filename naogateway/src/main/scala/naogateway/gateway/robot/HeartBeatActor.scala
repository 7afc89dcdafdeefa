package naogateway.gateway.robot

import scala.collection.immutable.Queue

import akka.actor.typed.scaladsl.{Behaviors, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior}

import naogateway.gateway.robot.RobotFrames.Outbound
import naogateway.wire.RpcCall
import naogateway.api.{LinkQuality, Priority}
import naogateway.gateway.HeartbeatSettings

/** Liveness of one robot: passive from keep-alives, active probes when it goes quiet, three chances, then offline. Its
  * probes go straight to the robot's sender (as the stream's segments do), which it tells when each was answered; its
  * verdicts and figures go to the robot actor.
  */
private[naogateway] object HeartBeatActor {

  /** What the heartbeat accepts. */
  sealed trait Command

  /** A keep-alive of the robot arrived. */
  private[naogateway] case object KeepAliveSeen extends Command

  /** Any reply with one of this heartbeat's call ids arrived (the probe's error reply proves the robot is there). */
  private[naogateway] final case class ProbeAnswered(callId: Long) extends Command

  /** Someone wants the robot: probe at once, even when it is offline. */
  private[naogateway] case object ProbeNow extends Command

  private case object QuietCheck extends Command
  private case object ProbeTimeout extends Command
  private case object QualityTick extends Command
  private case object BackoffOver extends Command

  /** What the heartbeat tells its robot actor. */
  sealed trait Report

  /** The heartbeat's verdicts on whether the robot is there: what changes its robot actor's state. */
  sealed trait Verdict extends Report

  /** The robot answered or spoke after being offline (or at first contact). */
  case object CameOnline extends Verdict

  /** The robot missed every chance. */
  final case class WentOffline(reason: String) extends Verdict

  /** The link quality crossed a threshold. */
  final case class QualityChanged(quality: LinkQuality) extends Report

  /** A probe's round trip, for the link statistics. */
  final case class ProbeRoundTrip(nanos: Long) extends Report

  /** The call that no robot serves: the robot's error reply proves it is there. */
  val ProbeModule: String = "heartbeat"
  val ProbeMethod: String = "probe"

  /** Keep-alives per tick over the quality window, the quality last reported, and how long it has looked good. */
  private final case class Quality(ticks: Queue[Int], current: Int, reported: LinkQuality, goodTicks: Int = 0) {
    def seen: Quality = copy(current = current + 1)

    def tick(settings: HeartbeatSettings, report: ActorRef[Report]): Quality = {
      val windowTicks = math.max(2, (settings.qualityWindow / settings.keepAliveInterval).toInt)
      val shifted = ticks.enqueue(current)
      val trimmed = if (shifted.size > windowTicks) shifted.dequeue._2 else shifted
      val ratio = trimmed.sum.toDouble / windowTicks
      val good = if (ratio > settings.goodAbove) goodTicks + 1 else 0
      // Judged only over a full window, with a gap between the two thresholds, and back to good only after a whole
      // window above the upper one: a link that hovers at the lower threshold stays degraded instead of flapping.
      val next =
        if (trimmed.size < windowTicks || reported == LinkQuality.Offline) reported
        else if (reported == LinkQuality.Good && ratio < settings.degradedBelow) LinkQuality.Degraded
        else if (reported == LinkQuality.Degraded && good >= windowTicks) LinkQuality.Good
        else reported
      if (next != reported) report ! QualityChanged(next)
      Quality(trimmed, 0, next, good)
    }

    def online: Quality = if (reported == LinkQuality.Offline) copy(reported = LinkQuality.Good) else this
  }

  private object Quality {
    val initial: Quality = Quality(Queue.empty, 0, LinkQuality.Offline)
  }

  private case object QuietKey
  private case object ProbeKey
  private case object QualityKey
  private case object BackoffKey

  /** A heartbeat reporting to `report` and probing through the robot's `sender`; `online` says whether the robot has
    * just been heard.
    */
  def apply(settings: HeartbeatSettings, report: ActorRef[Report], sender: ActorRef[NoResponseActor.Command],
      online: Boolean): Behavior[Command] =
    Behaviors.setup { _ =>
      Behaviors.withTimers { timers =>
        val h = new HeartBeat(settings, report, sender, timers)
        timers.startTimerWithFixedDelay(QualityKey, QualityTick, settings.keepAliveInterval)
        if (online) {
          val running = h.online(Quality.initial)
          report ! CameOnline
          running
        } else h.probe(chance = 1, wasOnline = false, Quality.initial)
      }
    }

  // Every step arms its timers before it reports: whoever reacts to a report (a test that then moves manual time,
  // say) finds the timers running already, so no timer starts late by the time that reaction took.
  private final class HeartBeat(settings: HeartbeatSettings, report: ActorRef[Report],
      sender: ActorRef[NoResponseActor.Command], timers: TimerScheduler[Command]) {
    // A random start per incarnation, as the response actor's: a late answer to a probe of an earlier incarnation
    // must not pass for an answer to this one's (protocol.md 7.1, a call id is never sent twice).
    private var nextProbeId = CallId.randomStart()
    private var probeSentAt = 0L
    private var probeId = -1L
    // Rounds of probes in a row that ended without an answer to any probe (a keep-alive does not count: anyone can send
    // one). After each, a new round for someone who wants the robot waits for the back-off (BackoffKey running);
    // `wanted` remembers that someone asked meanwhile.
    private var silentRounds = 0
    private var wanted = false

    private def armQuietCheck(): Unit = timers.startSingleTimer(QuietKey, QuietCheck, settings.quietAfter)

    def online(q: Quality): Behavior[Command] = {
      armQuietCheck()
      val quality = q.online
      onlineLoop(quality)
    }

    // The quality counted so far is held in a local `q` and the loop answers `Behaviors.same`: a new behaviour for
    // each keep-alive would re-wrap the actor's interceptors (its timers, its supervision) every time.
    private def onlineLoop(q0: Quality): Behavior[Command] = {
      var q = q0
      Behaviors.receiveMessage {
        case KeepAliveSeen =>
          armQuietCheck()
          q = q.seen
          Behaviors.same
        case QualityTick =>
          q = q.tick(settings, report)
          Behaviors.same
        case QuietCheck             => probe(chance = 1, wasOnline = true, q)
        case ProbeNow | BackoffOver => Behaviors.same
        case ProbeAnswered(id) =>
          if (answered(id)) reportRoundTrip()
          Behaviors.same
        case ProbeTimeout => Behaviors.same
      }
    }

    private def sendProbe(): Unit = {
      probeId = CallId.next(CallId.Owner.Heartbeat, nextProbeId)
      nextProbeId = CallId.count(probeId)
      probeSentAt = System.nanoTime()
      timers.startSingleTimer(ProbeKey, ProbeTimeout, settings.probeTimeout)
      // It takes room in the robot's buffer until answered, or until its timeout has passed.
      sender ! NoResponseActor.Submit(
        Outbound.CallOut(RpcCall(ProbeModule, ProbeMethod, Vector.empty, Some(probeId))),
        Priority.Heartbeat,
        Some(probeId),
        NoResponseActor.Awaits.Reply(Some(settings.probeTimeout))
      )
    }

    /** A reply to probe `id` arrived: its room in the robot's buffer is free (a probe's room is this actor's to free,
      * whether it still waits for that probe or not); true when it is the probe it waits for.
      */
    private def answered(id: Long): Boolean = {
      sender ! NoResponseActor.Finished(id)
      id == probeId
    }

    private def reportRoundTrip(): Unit = {
      report ! ProbeRoundTrip(System.nanoTime() - probeSentAt)
      probeId = -1L
      silentRounds = 0
      timers.cancel(BackoffKey)
    }

    def probe(chance: Int, wasOnline: Boolean, q: Quality): Behavior[Command] = {
      sendProbe()
      probing(chance, wasOnline, q)
    }

    private def backOnline(wasOnline: Boolean, q: Quality, probeAnswered: Boolean): Behavior[Command] = {
      timers.cancel(ProbeKey)
      val next = online(q)
      if (probeAnswered) reportRoundTrip()
      if (!wasOnline) report ! CameOnline
      next
    }

    private def probing(chance: Int, wasOnline: Boolean, q: Quality): Behavior[Command] = Behaviors.receiveMessage {
      case KeepAliveSeen => backOnline(wasOnline, q.seen, probeAnswered = false)
      case ProbeAnswered(id) =>
        if (answered(id)) backOnline(wasOnline, q, probeAnswered = true) else Behaviors.same
      case ProbeTimeout =>
        if (chance < settings.chances) probe(chance + 1, wasOnline, q)
        else {
          silentRounds += 1
          wanted = false
          timers.startSingleTimer(BackoffKey, BackoffOver, settings.probeBackoff(silentRounds))
          if (wasOnline) {
            report ! WentOffline(
              s"no keep-alive for ${settings.quietAfter.toMillis} ms and ${settings.chances} unanswered probes")
          }
          offline(q.copy(reported = LinkQuality.Offline, ticks = Queue.empty, current = 0))
        }
      case QualityTick                         => probing(chance, wasOnline, q.tick(settings, report))
      case QuietCheck | ProbeNow | BackoffOver => Behaviors.same
    }

    /* Offline: the heartbeat stops probing; the next keep-alive or someone's request starts it again. A request starts
     * a */
    // round only once the back-off after the silent rounds has passed (at once for a robot that answered last time).
    private def offline(q: Quality): Behavior[Command] = Behaviors.receiveMessage {
      case KeepAliveSeen =>
        timers.cancel(BackoffKey)
        backOnline(wasOnline = false, q.seen, probeAnswered = false)
      case ProbeNow =>
        if (timers.isTimerActive(BackoffKey)) {
          wanted = true
          Behaviors.same
        } else probe(chance = 1, wasOnline = false, q)
      case BackoffOver =>
        if (wanted) {
          wanted = false
          probe(chance = 1, wasOnline = false, q)
        } else Behaviors.same
      case ProbeAnswered(id) =>
        if (answered(id)) backOnline(wasOnline = false, q, probeAnswered = true) else Behaviors.same
      case QualityTick | QuietCheck | ProbeTimeout => Behaviors.same
    }
  }
}
