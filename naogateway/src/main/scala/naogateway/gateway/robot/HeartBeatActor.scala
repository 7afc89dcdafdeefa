package naogateway.gateway.robot

import java.util.concurrent.TimeUnit

import scala.collection.immutable.Queue
import scala.concurrent.duration.FiniteDuration

import akka.actor.typed.scaladsl.{Behaviors, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior}

import naogateway.gateway.robot.RobotFrames.Outbound
import naogateway.wire.RpcCall
import naogateway.api.{LinkQuality, Priority}
import naogateway.gateway.HeartbeatSettings
import naogateway.gateway.link.PortProgress

/** Liveness of one robot: passive from keep-alives, active probes when it goes quiet, three chances, then offline. Its
  * probes go straight to the robot's sender (as the stream's segments do), which it tells when each was answered; its
  * verdicts and figures go to the robot actor.
  *
  * The keep-alives reach it through [[KeepAlives]], a count and a time the robot actor writes and the heartbeat reads
  * on its own timers, not as a message each: at full load a message and a re-armed timer per keep-alive were a large
  * share of the port loop's work. Only while the heartbeat waits for the robot (probing or offline) does a keep-alive
  * also send it [[KeepAliveSeen]], so that it comes back online at once.
  */
private[naogateway] object HeartBeatActor {

  /** What the heartbeat accepts. */
  sealed trait Command

  /** A keep-alive was counted in [[KeepAlives]] while the heartbeat asked to be told (it waits for the robot). */
  private[naogateway] case object KeepAliveSeen extends Command

  /** Any reply with one of this heartbeat's call ids arrived (the probe's error reply proves the robot is there). */
  private[naogateway] final case class ProbeAnswered(callId: Long) extends Command

  /** Someone wants the robot: probe at once, even when it is offline. */
  private[naogateway] case object ProbeNow extends Command

  private case object QuietCheck extends Command
  private case object ProbeTimeout extends Command
  private[robot] case object QualityTick extends Command
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

  /** The robot's keep-alives as its robot actor counts them (one writer) and its heartbeat reads them: how many so far,
    * when the last one arrived (on `clock`, nanoseconds), and whether the heartbeat wants a [[KeepAliveSeen]] for each
    * (it does while it waits for the robot). Shared by the two actors of one robot, outliving the heartbeat's restarts.
    */
  final class KeepAlives(val clock: () => Long = () => System.nanoTime()) {
    @volatile private var seenCount = 0L
    @volatile private var lastNanos = 0L
    @volatile private var wanted = true

    /** A keep-alive arrived at `now` (on `clock`); true when the heartbeat is to be told with a message. The count is
      * written before the wish is read: a keep-alive counted after the heartbeat wished to be told is told, one counted
      * just before is found in the count when the heartbeat's probe times out.
      */
    def seen(now: Long): Boolean = {
      lastNanos = now
      seenCount = seenCount + 1
      wanted
    }

    /** Keep-alives so far. */
    def count: Long = seenCount

    /** When the latest keep-alive arrived (on `clock`). */
    def last: Long = lastNanos

    /** Whether a keep-alive is to be told with a message; the heartbeat's alone to set. */
    private[HeartBeatActor] def wantMessages(on: Boolean): Unit = wanted = on
  }

  /** Keep-alives per tick over the quality window, the quality last reported, and how long it has looked good. */
  private final case class Quality(ticks: Queue[Int], counted: Long, reported: LinkQuality, goodTicks: Int = 0) {

    /** One tick with the keep-alives counted since the last (`count` the count in [[KeepAlives]] now). */
    def tick(settings: HeartbeatSettings, report: ActorRef[Report], count: Long): Quality = {
      val windowTicks = math.max(2, (settings.qualityWindow / settings.keepAliveInterval).toInt)
      val shifted = ticks.enqueue((count - counted).toInt)
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
      Quality(trimmed, count, next, good)
    }

    def online: Quality = if (reported == LinkQuality.Offline) copy(reported = LinkQuality.Good) else this
  }

  private object Quality {

    /** Nothing judged yet; keep-alives counted from `count` on. */
    def initial(count: Long): Quality = Quality(Queue.empty, count, LinkQuality.Offline)
  }

  /** How often a probe's verdict looks again whether the port's reader has caught up. */
  private val ReaderCheck: FiniteDuration = FiniteDuration(20, TimeUnit.MILLISECONDS)

  // A probe whose timeout has not come yet.
  private val NotYet = Long.MinValue

  private case object QuietKey
  private case object ProbeKey
  private case object QualityKey
  private case object BackoffKey

  /** A heartbeat reporting to `report` and probing through the robot's `sender`, reading the robot's `keepAlives`;
    * `online` says whether the robot has just been heard. `port` is how far the reader of the robot's port has caught
    * up: a probe is not judged unanswered while its answer may still wait in the socket (at most `reader-grace`).
    */
  def apply(settings: HeartbeatSettings, report: ActorRef[Report], sender: ActorRef[NoResponseActor.Command],
      online: Boolean, keepAlives: KeepAlives, port: PortProgress = PortProgress.Always): Behavior[Command] =
    Behaviors.setup { _ =>
      Behaviors.withTimers { timers =>
        // Told of every keep-alive until it is online (and counts them from here on).
        keepAlives.wantMessages(true)
        val h = new HeartBeat(settings, report, sender, timers, keepAlives, port)
        timers.startTimerWithFixedDelay(QualityKey, QualityTick, settings.keepAliveInterval)
        if (online) {
          val running = h.online(Quality.initial(keepAlives.count))
          report ! CameOnline
          running
        } else h.probe(chance = 1, wasOnline = false, Quality.initial(keepAlives.count))
      }
    }

  // Every step arms its timers before it reports: whoever reacts to a report (a test that then moves manual time,
  // say) finds the timers running already, so no timer starts late by the time that reaction took.
  private final class HeartBeat(settings: HeartbeatSettings, report: ActorRef[Report],
      sender: ActorRef[NoResponseActor.Command], timers: TimerScheduler[Command], keepAlives: KeepAlives,
      port: PortProgress) {
    // A random start per incarnation, as the response actor's: a late answer to a probe of an earlier incarnation
    // must not pass for an answer to this one's (protocol.md 7.1, a call id is never sent twice).
    private var nextProbeId = CallId.randomStart()
    private var probeSentAt = 0L
    private var probeId = -1L
    /* When the current probe's timeout first came (NotYet before): from then on its verdict waits, within the grace,
     * for */
    // the port's reader to catch up with what the socket held at that moment.
    private var probeTimedOutAt = NotYet
    // Rounds of probes in a row that ended without an answer to any probe (a keep-alive does not count: anyone can send
    // one). After each, a new round for someone who wants the robot waits for the back-off (BackoffKey running);
    // `wanted` remembers that someone asked meanwhile.
    private var silentRounds = 0
    private var wanted = false

    private val quietNanos = settings.quietAfter.toNanos
    // The keep-alive count when the quiet check was armed (online) or the wait for the robot began (probing, offline):
    // read before the heartbeat asks to be told of keep-alives, so each later one is either counted beyond it or told.
    private var countAtCheck = keepAlives.count

    /** The quiet check, `quietAfter` after the latest keep-alive (or from now when none came since `countAtCheck`). */
    private def armQuietCheck(): Unit = {
      val count = keepAlives.count
      val wait =
        if (count == countAtCheck) quietNanos
        else math.max(1000000L, keepAlives.last + quietNanos - keepAlives.clock())
      countAtCheck = count
      timers.startSingleTimer(QuietKey, QuietCheck, FiniteDuration(wait, TimeUnit.NANOSECONDS))
    }

    /** Whether a keep-alive was counted since the wait began: one that came as the wait began may not have been told.
      */
    private def heard: Boolean = keepAlives.count != countAtCheck

    def online(q: Quality): Behavior[Command] = {
      keepAlives.wantMessages(false)
      countAtCheck = keepAlives.count
      armQuietCheck()
      val quality = q.online
      onlineLoop(quality)
    }

    // The quality counted so far is held in a local `q` and the loop answers `Behaviors.same`: a new behaviour for
    // each tick would re-wrap the actor's interceptors (its timers, its supervision) every time.
    private def onlineLoop(q0: Quality): Behavior[Command] = {
      var q = q0
      Behaviors.receiveMessage {
        case KeepAliveSeen => Behaviors.same // told just before the wish was withdrawn: counted already
        case QualityTick =>
          q = q.tick(settings, report, keepAlives.count)
          Behaviors.same
        case QuietCheck =>
          // Keep-alives since the check was armed: quiet only `quietAfter` after the latest of them.
          if (keepAlives.count != countAtCheck) {
            armQuietCheck()
            Behaviors.same
          } else {
            // A keep-alive from now on is told (or seen in the count by the probe's timeout, if it came just now).
            keepAlives.wantMessages(true)
            probe(chance = 1, wasOnline = true, q)
          }
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
      probeTimedOutAt = NotYet
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

    /** Whether the port's reader has not found its socket empty since this probe's timeout came, within the grace. */
    private def readerBehind(): Boolean = {
      // On the keep-alives' clock, as the port's progress is.
      val now = keepAlives.clock()
      if (probeTimedOutAt == NotYet) probeTimedOutAt = now
      !port.caughtUpSince(probeTimedOutAt) && now - probeTimedOutAt < settings.readerGrace.toNanos
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
      // Told only of a keep-alive counted after the wait began (the robot actor's first may even precede this actor).
      case KeepAliveSeen => backOnline(wasOnline, q, probeAnswered = false)
      case ProbeAnswered(id) =>
        if (answered(id)) backOnline(wasOnline, q, probeAnswered = true) else Behaviors.same
      case ProbeTimeout =>
        if (heard) backOnline(wasOnline, q, probeAnswered = false)
        else if (readerBehind()) {
          // A burst fills the socket: the answer or a keep-alive may be waiting behind it. Judged once the reader
          // found the socket empty, or when the grace is over.
          timers.startSingleTimer(ProbeKey, ProbeTimeout, ReaderCheck)
          Behaviors.same
        } else if (chance < settings.chances) probe(chance + 1, wasOnline, q)
        else {
          silentRounds += 1
          wanted = false
          timers.startSingleTimer(BackoffKey, BackoffOver, settings.probeBackoff(silentRounds))
          if (wasOnline) {
            report ! WentOffline(
              s"no keep-alive for ${settings.quietAfter.toMillis} ms and ${settings.chances} unanswered probes")
          }
          offline(q.copy(reported = LinkQuality.Offline, ticks = Queue.empty, counted = countAtCheck))
        }
      case QualityTick                         => probing(chance, wasOnline, q.tick(settings, report, keepAlives.count))
      case QuietCheck | ProbeNow | BackoffOver => Behaviors.same
    }

    /* Offline: the heartbeat stops probing; the next keep-alive or someone's request starts it again. A request starts
     * a */
    // round only once the back-off after the silent rounds has passed (at once for a robot that answered last time).
    private def offline(q: Quality): Behavior[Command] = Behaviors.receiveMessage {
      case KeepAliveSeen =>
        timers.cancel(BackoffKey)
        backOnline(wasOnline = false, q, probeAnswered = false)
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
