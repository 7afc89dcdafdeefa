package naogateway.gateway.robot

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.actor.typed.ActorRef

import naogateway.proto.{DebuggingCommands, DebuggingOption, RobotHealth, ServoTelemetry, Status}
import naogateway.wire.HeaderForm
import naogateway.api.{
  GatewayEvent,
  LinkQuality,
  LinkStats,
  RobotSnapshot,
  RobotStatusUpdated,
  SigningState,
  VisionFrame
}
import naogateway.gateway.Rejection

/** The link figures of one robot as its robot actor counts them (what leaves is counted by its sender,
  * [[SentFigures]]). `keepAliveTimes` holds the keep-alives' arrival times, oldest first, never more than
  * `keepAliveTimesKept`: with more than a window's worth the loss estimate is 0 anyway, so a flooding robot costs what
  * a punctual one costs.
  */
private[naogateway] final case class LinkFigures(
    datagramsIn: Long = 0L,
    bytesIn: Long = 0L,
    retransmissions: Long = 0L,
    rejected: Map[Rejection, Long] = Map.empty,
    rttNanos: Option[Double] = None,
    keepAliveTimes: ArrivalTimes = ArrivalTimes.empty
) {

  /** The share of keep-alives missed over `window` (or since the first one, when the robot is younger) at `now`. */
  def lossEstimate(now: Long, window: Long, interval: Long): Double = {
    val first = keepAliveTimes.firstFrom(now - window)
    val recent = keepAliveTimes.countFrom(now - window)
    val observed = if (recent == 0) window else math.min(window, now - first + interval)
    if (datagramsIn == 0) 1.0 else math.max(0.0, 1.0 - recent / (observed.toDouble / interval))
  }
}

/** Arrival times in nanoseconds, oldest first: the slots `[from, until)` of a buffer shared with the earlier and later
  * values of the same robot. An immutable value all the same: a slot is written once, before any value holds it, and
  * only the latest value appends in place (into the buffer's next free slot); appending to any other value, or to a
  * full buffer, copies what is kept into a new buffer with room to spare. Why: a keep-alive appended to a Vector of
  * boxed times copied two arrays and boxed the time, and a new array per keep-alive was still 12 % of the bytes the
  * port loop allocates under an ingest blast (profiled); in place, a keep-alive costs this small value, and the kept
  * times are copied once every `Spare` keep-alives.
  */
private[naogateway] final class ArrivalTimes private (private val buffer: ArrivalTimes.Buffer, private val from: Int,
    private val until: Int) {

  /** How many times are held. */
  def size: Int = until - from

  /** The times, oldest first. */
  def toVector: Vector[Long] = (from until until).map(buffer.times(_)).toVector

  /** These times with `now` appended: at most `kept` of them (the oldest go first), none older than `window` before
    * `now`.
    */
  def appended(now: Long, window: Long, kept: Int): ArrivalTimes = {
    val oldest = now - window
    val times = buffer.times
    var start = math.max(from, until + 1 - kept)
    while (start < until && times(start) < oldest) start += 1
    if (until == buffer.used && until < times.length) {
      times(until) = now
      buffer.used = until + 1
      new ArrivalTimes(buffer, start, until + 1)
    } else {
      val n = until - start
      val next = new ArrivalTimes.Buffer(new Array[Long](n + 1 + ArrivalTimes.Spare))
      System.arraycopy(times, start, next.times, 0, n)
      next.times(n) = now
      next.used = n + 1
      new ArrivalTimes(next, 0, n + 1)
    }
  }

  /** How many times are at or after `t`. */
  def countFrom(t: Long): Int = until - indexFrom(t)

  /** The first time at or after `t`; meaningful only when [[countFrom]] is positive. */
  def firstFrom(t: Long): Long = {
    val i = indexFrom(t)
    if (i < until) buffer.times(i) else Long.MaxValue
  }

  // The times are in arrival order, so those at or after `t` are a suffix.
  private def indexFrom(t: Long): Int = {
    var i = from
    while (i < until && buffer.times(i) < t) i += 1
    i
  }

  override def equals(other: Any): Boolean = other match {
    case o: ArrivalTimes =>
      java.util.Arrays.equals(buffer.times, from, until, o.buffer.times, o.from, o.until)
    case _ => false
  }

  override def hashCode: Int = toVector.hashCode

  override def toString: String = toVector.mkString("ArrivalTimes(", ", ", ")")

}

/** Arrival times. */
private[naogateway] object ArrivalTimes {

  /** Slots a new buffer has beyond the times it starts with: the appends until the next copy. */
  private val Spare = 64

  /** The times, and how many of its slots have been written (by the latest value, the only one that appends in place).
    * One robot actor's alone: neither is read by any other thread.
    */
  private final class Buffer(val times: Array[Long]) {
    var used = 0
  }

  /** No time yet. */
  def empty: ArrivalTimes = new ArrivalTimes(new Buffer(new Array[Long](Spare)), 0, 0)

  /** `times`, oldest first. */
  def apply(times: Long*): ArrivalTimes = {
    val b = new Buffer(times.toArray ++ new Array[Long](Spare))
    b.used = times.length
    new ArrivalTimes(b, 0, times.length)
  }
}

/** The robot's debug options (protocol.md 8): what the gateway switched on, and this session's list once pushed. */
private[naogateway] final case class RobotOptions(
    active: Set[String] = Set.empty,
    list: Option[Seq[DebuggingOption]] = None,
    pulling: Boolean = false,
    pulls: Long = 0L
) {

  /** The key of the latest `optionPull` in the robot's sender: below every call id, above the sender's own keys. */
  def pullKey: Long = -1L - pulls

  /** `commands` noted: enabled options join, disabled ones (and their sub-options) leave. */
  def noted(commands: DebuggingCommands): RobotOptions = {
    val enabled = commands.optionEnable.fold(active)(e => active ++ e.options)
    val off = commands.optionDisable.fold(Seq.empty[String])(_.options)
    copy(active = enabled.filterNot(o => off.exists(RobotOptions.covers(_, o))))
  }
}

/** The option rules. */
private[naogateway] object RobotOptions {

  /** How often `optionPull` is repeated until the robot's `optionPush` arrives. Fixed, not a setting: protocol.md 8,
    * step 1 gives robots this period ("about every second"), and a robot's firmware is written against it.
    */
  val PullInterval: FiniteDuration = 1.second

  /** Whether option name `n` names option `o` or a group it belongs to (`havimo` covers `havimo.grid`). */
  def covers(n: String, o: String): Boolean = o == n || o.startsWith(n + ".")
}

/** What one keep-alive did: whether it completed a new session, and whether the heartbeat is to hear of it. */
private[naogateway] final case class KeepAliveOutcome(restarted: Boolean, heard: Boolean)

/** Everything a robot actor knows, as one immutable value: its address and header form, the latest keep-alive's
  * snapshot, the restart rule and clock sync, the debug options, its event subscribers (and events held until they are
  * known), the camera streams, and the link figures. Each change is a named transition; `RobotActor` only carries them
  * out, so everything here is tested without actors (RobotStateSpec).
  */
private[naogateway] final case class RobotState(
    robotId: Int,
    address: InetSocketAddress,
    form: HeaderForm,
    snapshot: RobotSnapshot,
    sessions: SessionRule,
    introducing: Boolean,
    clockSync: ClockSync,
    options: RobotOptions,
    subscribers: Option[Set[ActorRef[GatewayEvent]]],
    statusSubscribers: Set[ActorRef[GatewayEvent]],
    held: Vector[GatewayEvent],
    vision: Map[ActorRef[VisionFrame], Boolean],
    link: LinkFigures,
    keepAliveTimesKept: Int
) {

  /** A frame of `size` bytes in `frameForm` arrived; true when its form differs from the last (the route changes). */
  def frameReceived(size: Int, frameForm: HeaderForm): (RobotState, Boolean) =
    (copy(form = frameForm, link = link.copy(datagramsIn = link.datagramsIn + 1, bytesIn = link.bytesIn + size)),
      frameForm != form)

  /** A secure-stream segment of `size` bytes arrived. */
  def segmentReceived(size: Int): RobotState =
    copy(link = link.copy(datagramsIn = link.datagramsIn + 1, bytesIn = link.bytesIn + size))

  /** A datagram of this robot was refused for `kind`; with how many of that kind so far. */
  def refused(kind: Rejection): (RobotState, Long) = {
    val n = link.rejected.getOrElse(kind, 0L) + 1
    (copy(link = link.copy(rejected = link.rejected.updated(kind, n))), n)
  }

  /** A frame of a robot that must sign passed its signature check: the robot is shown as signing. */
  def signatureAccepted: RobotState =
    if (snapshot.signing == SigningState.Off || snapshot.signing == SigningState.Signed) this
    else copy(snapshot = snapshot.copy(signing = SigningState.Signed))

  /** A datagram of a robot that must sign was refused for `kind`: unsigned or badly signed, the robot is shown as
    * `unsigned` unless its own signed frames keep coming (anyone can send a forged frame from its address, and a replay
    * is never the robot's doing: neither changes what is shown of a robot that signs).
    */
  def signatureRefused(kind: Rejection): RobotState =
    if (snapshot.signing == SigningState.Off || snapshot.signing == SigningState.Signed ||
      !RobotState.UnsignedKinds(kind)) this
    else copy(snapshot = snapshot.copy(signing = SigningState.Unsigned))

  /** The robot went offline: whether it still signs is open again (a robot restarted with a firmware that does not sign
    * shows as `unsigned` from its next refused frame on).
    */
  def signatureUnconfirmed: RobotState =
    if (snapshot.signing == SigningState.Signed) copy(snapshot = snapshot.copy(signing = SigningState.Awaited))
    else this

  /** The robot went offline: its servo telemetry is no longer known (docs/protocol.md 6.8), and whether it still signs
    * is open again (`signatureUnconfirmed`).
    */
  def wentOffline: RobotState = {
    val s = signatureUnconfirmed
    if (s.snapshot.servos.isEmpty && !s.snapshot.online) s
    else s.copy(snapshot = s.snapshot.copy(servos = None, online = false))
  }

  /** A clean round-trip sample, smoothed as TCP smooths its RTT. */
  def roundTrip(nanos: Long): RobotState =
    copy(link = link.copy(rttNanos = Some(link.rttNanos.fold(nanos.toDouble)(r => r * 0.875 + nanos * 0.125))))

  /** A call was sent again. */
  def retransmitted: RobotState = copy(link = link.copy(retransmissions = link.retransmissions + 1))

  /** A keep-alive arrived at `now` (`window`: the quality window in nanoseconds). A discovered robot's first one (the
    * one that introduced it) is not passed on to the heartbeat: anyone can send one.
    */
  def keepAliveSeen(status: Status, health: Option[RobotHealth], now: Long, window: Long, newSessionKeepAlives: Int,
      servos: Option[ServoTelemetry] = None): (RobotState, KeepAliveOutcome) = {
    val times = link.keepAliveTimes.appended(now, window, keepAliveTimesKept)
    val step = KeepAliveStep.keepAlive(snapshot, sessions, status, health, now, newSessionKeepAlives, servos)
    val restartedSync = if (step.restarted) clockSync.restart else clockSync
    // Status.timestamp is the robot's clock (64 bits); RobotHealth.uptimeMs (32 bits) only stands in for it. Matches,
    // not folds and maps: this runs for every keep-alive, and each function passed would be built for it.
    val robotTime = status.timestamp match {
      case None =>
        health match {
          case Some(h) =>
            h.uptimeMs match {
              case Some(uptime) => Some(restartedSync.unwrap32(uptime.toLong))
              case None         => None
            }
          case None => None
        }
      case robotClock => robotClock
    }
    val sync = robotTime match {
      case Some(t) => restartedSync.add(t, now)
      case None    => restartedSync
    }
    val clock = sync.estimate
    val stamped = (robotTime, clock) match {
      case (Some(t), Some(c)) => Some(c.toGatewayNanos(t))
      case _                  => None
    }
    val next = copy(
      snapshot = step.snapshot.copy(clock = clock, stampedAtNanos = stamped),
      sessions = step.sessions,
      introducing = false,
      clockSync = sync,
      link = link.copy(keepAliveTimes = times)
    )
    (next, KeepAliveOutcome(step.restarted, heard = !introducing))
  }

  /** The robot now receives at `to` (it moved host). */
  def rebound(to: InetSocketAddress): RobotState = copy(address = to, snapshot = snapshot.copy(address = to))

  /** The heartbeat judged the link `quality`. */
  def qualityChanged(quality: LinkQuality): RobotState = copy(snapshot = snapshot.copy(quality = quality))

  /** The robot came online: its quality starts good (HeartBeatActor's rule). */
  def wentOnline: RobotState = copy(snapshot = snapshot.copy(online = true, quality = LinkQuality.Good))

  /** The snapshot as it leaves the actor: `online` from the behaviour, the quality offline while offline. */
  def view(online: Boolean): RobotSnapshot = {
    val quality = if (online) snapshot.quality else LinkQuality.Offline
    // The snapshot itself when it says so already (`wentOnline` and `wentOffline` keep its `online`): no copy for each
    // keep-alive's event.
    if (snapshot.online == online && snapshot.quality == quality) snapshot
    else snapshot.copy(online = online, quality = quality)
  }

  /** The link figures as `LinkStats` at `now`, with what the sender counted as it sent (`out`). */
  def linkStats(now: Long, window: Long, interval: Long, out: SentFigures): LinkStats =
    LinkStats(
      robotId,
      link.datagramsIn,
      out.datagrams,
      link.bytesIn,
      out.bytes,
      link.rttNanos.map(_ / 1e6),
      link.lossEstimate(now, window, interval),
      link.retransmissions,
      link.rejected.map { case (k, n) => k.name -> n },
      clockSync.estimate
    )

  /** An option command from a child: noted, and whether it goes now (not while the pulled list is awaited, step 4). */
  def optionCommand(commands: DebuggingCommands): (RobotState, Boolean) =
    (copy(options = options.noted(commands)), !options.pulling || commands.optionPull.nonEmpty)

  /** A new session's option pull starts (protocol.md 8, step 1): its list is unknown again. */
  def pullStarted: RobotState = copy(options = options.copy(pulling = true, list = None))

  /** One more `optionPull` goes out; its key in the sender. */
  def pullSent: (RobotState, Long) = {
    val next = copy(options = options.copy(pulls = options.pulls + 1))
    (next, next.options.pullKey)
  }

  /** The robot pushed its option list (steps 2, 3). The first push of a pull lets the options we want go out (step 4):
    * those it offers, sorted; the others it does not offer are returned to be logged.
    */
  def optionsPushed(list: Seq[DebuggingOption]): (RobotState, Vector[String], Vector[String]) =
    if (!options.pulling) (copy(options = options.copy(list = Some(list))), Vector.empty, Vector.empty)
    else {
      val offered = list.map(_.name)
      val (known, unknown) = options.active.toVector.sorted.partition(n => offered.exists(RobotOptions.covers(n, _)))
      (copy(options = options.copy(list = Some(list), pulling = false)), known, unknown)
    }

  /** The gateway's subscribers now, of which `statusless` get no `RobotStatusUpdated` (the recorder: it reads the
    * status off the tap); the events held meanwhile go to them (returned, oldest first, for [[recipients]]).
    */
  def subscribersChanged(now: Set[ActorRef[GatewayEvent]],
      statusless: Set[ActorRef[GatewayEvent]] = Set.empty): (RobotState, Vector[GatewayEvent]) =
    (copy(subscribers = Some(now), statusSubscribers = now -- statusless, held = Vector.empty), held)

  /** Whether a `RobotStatusUpdated` would reach anyone (or be held while the subscribers are unknown): when not, the
    * keep-alive builds none.
    */
  def wantsStatus: Boolean = subscribers.isEmpty || statusSubscribers.nonEmpty

  /** The subscribers `event` goes to: a `RobotStatusUpdated` to those that want the status. */
  def recipients(event: GatewayEvent): Set[ActorRef[GatewayEvent]] = event match {
    case _: RobotStatusUpdated => statusSubscribers
    case _                     => subscribers.getOrElse(Set.empty)
  }

  /** `event` is published: to the subscribers returned, or held while they are unknown (at most
    * `RobotState.HeldEvents`: the gateway answers within one of its messages, but a silent gateway must cost no
    * memory).
    */
  def publish(event: GatewayEvent): (RobotState, Set[ActorRef[GatewayEvent]]) = subscribers match {
    case Some(_) => (this, recipients(event))
    case None    => (if (held.size < RobotState.HeldEvents) copy(held = held :+ event) else this, Set.empty)
  }

  /** A camera stream subscribed (or changed whether it wants grid frames); true when it is new (to be watched). */
  def visionSubscribed(subscriber: ActorRef[VisionFrame], grid: Boolean): (RobotState, Boolean) =
    (copy(vision = vision.updated(subscriber, grid)), !vision.contains(subscriber))

  /** A camera stream stopped. */
  def visionGone(subscriber: ActorRef[VisionFrame]): RobotState = copy(vision = vision - subscriber)
}

/** Robot states. */
private[naogateway] object RobotState {

  /** Events a robot actor holds while it waits for the gateway's subscriber list. */
  val HeldEvents: Int = 64

  /** The refusals that show a robot that must sign as `unsigned`: its frames carry no valid signature. */
  val UnsignedKinds: Set[Rejection] =
    Set(Rejection.Unsigned, Rejection.SignatureNotLast, Rejection.MalformedSignature, Rejection.BadSignature)

  /** The state of robot `robotId` at `address` before anything was heard; `subscribers` None when the gateway is still
    * to say; a `discovered` robot's first keep-alive only introduces it. `keepAliveTimesKept` bounds the loss window.
    * `signs`: the robot must sign its frames.
    */
  def initial(robotId: Int, address: InetSocketAddress, clockSync: ClockSync,
      subscribers: Option[Set[ActorRef[GatewayEvent]]], discovered: Boolean, keepAliveTimesKept: Int,
      signs: Boolean = false): RobotState =
    RobotState(
      robotId,
      address,
      HeaderForm.Legacy,
      RobotSnapshot(robotId, address, signing = if (signs) SigningState.Awaited else SigningState.Off),
      SessionRule.empty,
      discovered,
      clockSync,
      RobotOptions(),
      subscribers,
      subscribers.getOrElse(Set.empty),
      Vector.empty,
      Map.empty,
      LinkFigures(),
      keepAliveTimesKept
    )
}
