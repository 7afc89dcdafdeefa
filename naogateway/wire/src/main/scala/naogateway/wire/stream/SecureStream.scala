package naogateway.wire.stream

import scala.collection.immutable.{Queue, TreeSet}

import naogateway.wire.WireLimits

/** One endpoint of the secure stream (docs/protocol.md §11): reliable, ordered delivery over UDP with the thesis's
  * 2-byte header, as a pure state machine.
  *
  * Every transition takes the current time in nanoseconds (simulated or monotonic; only differences matter) and returns
  * a new state plus the outputs to act on: datagrams to transmit, payloads to deliver, and the fate of the payloads
  * this side sent. The state is immutable and holds no clock, thread or timer: the owner calls [[tick]] when
  * [[nextTimerAt]] has come.
  *
  * Bytes: a payload passed to [[send]] is copied, so the caller may reuse its array; [[receive]] only reads its
  * argument; every array in an output is fresh and belongs to the receiver of the output.
  *
  * ==Rules==
  *   1. A segment is a 2-byte header plus payload. Byte 0 is the sender's own sequence number, byte 1 the ACK: the
  *      sequence number of the last segment received in order from the peer (cumulative). A segment without payload is
  *      a pure ACK; every data segment acknowledges as well (piggybacking).
  *   1. Sequence numbers run from 0 to maxSeq (at most 41; the thesis firmware uses 20) and wrap. The first data
  *      segment has number 0. Before anything has arrived the ACK byte is maxSeq ("the one before 0"), and the sender's
  *      "last acknowledged" starts at maxSeq too.
  *   1. A payload has 1 to 1398 bytes (header plus payload at most 1400). An empty or larger payload is refused when it
  *      is sent, and so is a send while `sendQueueLimit` payloads are waiting. Nothing is dropped silently.
  *   1. The window W (1 to 20, with 2W <= maxSeq + 1) is the number of data segments that may be unacknowledged at
  *      once. At W = 1 segment n is sent only once n - 1 is acknowledged: the thesis protocol.
  *   1. A data segment numbered within [expected, expected + W - 1] is new: the expected one is delivered at once
  *      (followed by any buffered successors), a later one is buffered (only possible at W > 1). One within [expected -
  *      W, expected - 1] is a duplicate and is dropped. Every data segment received, new or duplicate, is answered at
  *      once with an ACK, piggybacked on new data when this side has some to send at that moment, otherwise as a pure
  *      ACK. A pure ACK is never answered, except a skip notice that was acted on (rule 11).
  *   1. An ACK within [last acknowledged, last sent] acknowledges everything up to it. An ACK at most W behind the last
  *      acknowledged one is stale (overtaken on the way): only its ACK byte is disregarded. A datagram that is shorter
  *      than 2 or longer than 1400 bytes, carries a number above maxSeq, a sequence number outside both ranges of rule
  *      5 or an ACK for something never sent is misbehaving: it is ignored as a whole and counted. Receiving never
  *      throws.
  *   1. One retransmission timer runs for the oldest unacknowledged segment. When it expires only that segment is sent
  *      again and the timeout doubles (up to maxRto). At W > 1 only: two duplicate pure ACKs resend the oldest segment
  *      once per recovery (fast retransmit), and an ACK that advances but does not cover everything sent before the
  *      loss was noticed resends the new oldest segment at once (partial ACK, as in NewReno). A resent oldest segment
  *      is itself taken as lost, and sent again at once, when two more duplicate pure ACKs arrive after it than the
  *      segments ahead of it can explain: those sent after the latest transmission among the segments the last
  *      advancing ACK covered, and before the resend (the link keeps order, so earlier ones were answered with an older
  *      ACK). So only missing segments are sent again, and a lost resend need not wait for the timer. There is no fast
  *      retransmit at W = 1.
  *   1. The timeout adapts as in RFC 6298: SRTT and RTTVAR with alpha 1/8 and beta 1/4, RTO = SRTT + max(1 ms, 4
  *      RTTVAR) kept within [minRto, maxRto], initialRto before the first sample. Karn's rule: an ACK gives a sample
  *      only from the newest segment it covers, and only if that segment was sent once and nothing else the ACK covers
  *      was sent after it. A clean sample ends any back-off; an ACK that acknowledges new data without giving a sample
  *      keeps at most one doubling (see [[RtoEstimator.afterProgress]]).
  *   1. Idle ACK: an endpoint that has received data (or acted on a skip notice) since its last idle ACK, and has
  *      nothing unacknowledged, sends one pure ACK once it has sent nothing for idleAckInterval. It repeats the last
  *      ACK in case that was lost, once: a fresh or reset endpoint, and one whose peer has sent nothing new since,
  *      stays silent. Liveness is the keep-alive's job (protocol.md 6.2), so an idle stream costs the robot's module
  *      buffer nothing.
  *   1. A payload may carry a deadline. Once the deadline is reached, a payload still waiting in the queue is dropped
  *      without using a sequence number, and a sent one is no longer retransmitted; both are reported `Expired`. Byte 0
  *      of every pure ACK is the sender's "settled" number, the last sequence number such that it and all earlier ones
  *      are acknowledged or expired, announced at most one step past the peer's last ACK. Normally it equals that ACK
  *      and means nothing new. When the oldest unacknowledged segment expires, a pure ACK naming it goes out at once (a
  *      skip notice) and is repeated by the retransmission timer until the peer's ACK has passed it; several expired
  *      segments in a row are announced one per round trip.
  *   1. A receiver that honours skip notices (`honourSkipNotices`, default on) and gets a pure ACK whose byte 0 is
  *      exactly its next expected number treats that segment as expired: it delivers it if it is buffered and otherwise
  *      counts it as skipped, takes it as its last in-order number, delivers the buffered successors and answers with
  *      an ACK. Only the next number is accepted, not the whole window, because byte 0 of an ordinary pure ACK lags
  *      behind the receiver by up to W numbers (its sender has not heard the latest ACKs yet), and by more when data
  *      segments overtake it; with 42 numbers and W = 20 such a lagging ACK falls into [expected, expected + W - 1] and
  *      would skip data that is still on its way. A peer running the thesis firmware puts its own, possibly
  *      unacknowledged, number into byte 0 of pure ACKs, so against it the setting must be off, and payloads sent to it
  *      must carry no deadline: with nobody honouring the notice the stream would stall behind an expired segment.
  *   1. `Expired` means the sender stopped sending the payload before it was acknowledged. A copy already on its way
  *      may still be delivered before the skip notice arrives, but never after it; no payload is delivered twice or out
  *      of order.
  *   1. Sequence numbers repeat every N = maxSeq + 1 segments, and a receiver that holds segment m accepts the numbers
  *      of m + 1 to m + W as new; the last of them is also the number of segment m + W - N, acknowledged long ago. A
  *      late copy of that old segment would pass for new data. Hence segment m is not sent while segment m - (N - W)
  *      was sent again within the last smoothed round trip (minRto before the first sample). First transmissions never
  *      wait, as a full round trip always lies between them, and at W = 1 the segment in question is 20 segments old,
  *      so the rule does not delay the thesis protocol.
  *   1. Beyond that, as with TCP's maximum segment lifetime, the protocol assumes that no copy of a segment stays in
  *      the network much longer than about one round trip more than the datagrams sent after it. A single WLAN hop does
  *      not hold datagrams that long.
  *   1. `reset` puts the sequence state back to the start (for a peer that restarted, so both ends start afresh).
  *      Unacknowledged and queued payloads are kept and sent again from number 0: at-least-once across a restart.
  */
final class SecureStream private[stream] (
    val settings: StreamSettings,
    private[stream] val lastAckedSeq: Int,
    private[stream] val nextSeqNo: Int,
    private[stream] val slots: Vector[SecureStream.Slot],
    private[stream] val queue: Queue[SecureStream.Pending],
    private[stream] val queuedCount: Int,
    private[stream] val dropped: Set[Long],
    private[stream] val deadlines: TreeSet[SecureStream.DeadlineKey],
    private[stream] val nextSerial: Long,
    val rtoEstimator: RtoEstimator,
    private[stream] val rtxAt: Long,
    private[stream] val dupAcks: Int,
    private[stream] val recoverSeq: Int,
    private[stream] val rtxAhead: Int,
    private[stream] val dupAcksSinceRtx: Int,
    private[stream] val coveredSentAt: Long,
    private[stream] val lastInOrderSeq: Int,
    private[stream] val buffer: Map[Int, Array[Byte]],
    private[stream] val lastTransmitAt: Long,
    private[stream] val idleAckOwed: Boolean,
    private[stream] val retransmittedAt: Vector[Long],
    private[stream] val reuseBlockedUntil: Long,
    val stats: StreamStats
) {
  import SecureStream._

  /** The peer's cumulative ACK: the last own sequence number known to have arrived. */
  def lastAcknowledged: Int = lastAckedSeq

  /** The sequence number the next new data segment will carry. */
  def nextSequence: Int = nextSeqNo

  /** The last sequence number received from the peer in order (the ACK byte this side sends). */
  def lastInOrder: Int = lastInOrderSeq

  /** The last own sequence number such that it and every earlier one is acknowledged or expired; pure ACKs announce it
    * at most one step past the peer's last ACK.
    */
  def settled: Int = {
    var k = 0
    while (k < slots.length && slots(k).expired) k += 1
    (lastAckedSeq + k) % settings.sequenceSpace
  }

  /** Data segments sent and not yet acknowledged, including expired ones the peer has not yet skipped. */
  def inFlight: Int = slots.length

  /** Payloads waiting for a free window slot. */
  def queued: Int = queuedCount

  /** Segments received out of order and held until the gap before them closes. */
  def buffered: Int = buffer.size

  /** The current retransmission timeout in nanoseconds. */
  def rtoNanos: Long = rtoEstimator.rtoNanos

  /** The smoothed round-trip time in nanoseconds, once there has been a sample. */
  def smoothedRttNanos: Option[Long] = if (rtoEstimator.hasSample) Some(rtoEstimator.srttNanos) else None

  /** Whether an idle ACK is due once nothing has been sent for idleAckInterval (data arrived since the last one). */
  def idleAckDue: Boolean = idleAckOwed

  /** When [[tick]] must be called next: retransmission, the earliest deadline, or the idle ACK. */
  val nextTimerAt: Option[Long] = {
    var t = Long.MaxValue
    if (rtxAt != NoTime) t = rtxAt
    if (deadlines.nonEmpty) t = math.min(t, deadlines.firstKey.deadline)
    if (slots.isEmpty && idleAckOwed) t = math.min(t, lastTransmitAt + settings.idleAckNanos)
    if (reuseBlockedUntil != NoTime) t = math.min(t, reuseBlockedUntil)
    if (t == Long.MaxValue) None else Some(t)
  }

  /** Offers a payload for reliable delivery; `id` comes back in `Acknowledged` or `Expired`.
    *
    * A refusal leaves the state unchanged. Otherwise the payload is queued and sent as soon as the window allows,
    * possibly in the returned step. A `deadline` (same clock as `now`) that has already been reached expires the
    * payload at once.
    */
  def send(payload: Array[Byte], id: Long, deadline: Option[Long], now: Long): Either[SendRefused, Step] =
    if (payload.length == 0) Left(SendRefused.EmptyPayload(id))
    else if (payload.length > MaxPayloadBytes) Left(SendRefused.PayloadTooLarge(id, payload.length, MaxPayloadBytes))
    else if (queuedCount >= settings.sendQueueLimit) Left(SendRefused.SendQueueFull(id, settings.sendQueueLimit))
    else {
      val work = new SecureStreamWork(this, now)
      work.enqueue(payload.clone(), id, deadline.getOrElse(NoDeadline))
      Right(work.result())
    }

  /** Takes one datagram from the peer, header included; malformed or misbehaving ones are counted and ignored. */
  def receive(datagram: Array[Byte], now: Long): Step = {
    val work = new SecureStreamWork(this, now)
    work.receive(datagram)
    work.result()
  }

  /** Handles whatever is due at `now`: expiry, retransmission, keep-alive. Calling it early is harmless. */
  def tick(now: Long): Step = {
    val work = new SecureStreamWork(this, now)
    work.tick()
    work.result()
  }

  /** Starts the sequence state afresh for a peer that restarted, keeping unacknowledged and queued payloads (they are
    * sent again from sequence number 0), the round-trip estimate and the stats.
    */
  def reset(now: Long): Step = {
    val carried: Vector[Pending] =
      slots.filterNot(_.expired).map(s => Pending(s.serial, s.id, s.payload, s.deadline)) ++
        queue.filterNot(p => dropped.contains(p.serial))
    val fresh = start(settings, now, Queue.from(carried), deadlines, nextSerial, rtoEstimator, retransmittedAt, stats)
    val work = new SecureStreamWork(fresh, now)
    work.tick()
    work.result()
  }

  override def toString: String =
    s"SecureStream(window=${settings.window}, next=$nextSeqNo, lastAcked=$lastAckedSeq, inFlight=${slots.length}, " +
      s"queued=$queuedCount, lastInOrder=$lastInOrderSeq, buffered=${buffer.size}, rto=${rtoEstimator.rtoNanos}ns)"
}

/** Construction, outputs and refusals of [[SecureStream]]. */
object SecureStream {

  /** Bytes of the segment header: own sequence number and cumulative ACK. */
  val HeaderBytes: Int = 2

  /** The largest payload: the module's 1400-byte datagram limit minus the header. */
  val MaxPayloadBytes: Int = WireLimits.MaxDatagramBytes - HeaderBytes

  /** Duplicate pure ACKs that start a fast retransmit at window > 1. */
  val FastRetransmitThreshold: Int = 2

  /** Something the owner of the stream must act on. */
  sealed trait Output extends Product with Serializable

  /** A datagram to hand to the link, header included. */
  final case class Transmit(datagram: Array[Byte]) extends Output

  /** The next payload from the peer, in order, delivered once. */
  final case class Deliver(payload: Array[Byte]) extends Output

  /** The peer has received the payload sent with this id. */
  final case class Acknowledged(id: Long) extends Output

  /** The payload sent with this id reached its deadline unacknowledged; it is no longer sent. */
  final case class Expired(id: Long) extends Output

  /** The state after a transition and what to do about it, in order. */
  final case class Step(state: SecureStream, outputs: Vector[Output])

  /** Why a payload was not accepted for sending; the state is then unchanged. */
  sealed trait SendRefused extends Product with Serializable {

    /** The id the caller gave the payload. */
    def id: Long

    /** A short text for logs and error replies. */
    def describe: String
  }

  /** The reasons a send can be refused. */
  object SendRefused {

    /** Payloads must have at least one byte: a header alone is a pure ACK. */
    final case class EmptyPayload(id: Long) extends SendRefused {
      def describe: String = s"payload $id is empty"
    }

    /** The payload would not fit into one datagram of the module. */
    final case class PayloadTooLarge(id: Long, size: Int, maxPayload: Int) extends SendRefused {
      def describe: String = s"payload $id has $size bytes, at most $maxPayload fit into one segment"
    }

    /** The send queue already holds `limit` payloads. */
    final case class SendQueueFull(id: Long, limit: Int) extends SendRefused {
      def describe: String = s"payload $id refused: the send queue holds its limit of $limit payloads"
    }
  }

  /** A fresh endpoint: nothing sent, nothing received, so nothing to send until a payload is offered or data arrives.
    */
  def initial(settings: StreamSettings, now: Long): SecureStream =
    start(
      settings,
      now,
      queue = Queue.empty,
      deadlines = TreeSet.empty[DeadlineKey],
      nextSerial = 0L,
      rtoEstimator = RtoEstimator.initial(settings),
      retransmittedAt = Vector.fill(settings.sequenceSpace)(NoTime),
      stats = StreamStats.zero
    )

  /** The sequence state at its start (nothing in flight, nothing received, sequence numbers from 0), for a fresh
    * endpoint and for one whose peer restarted alike; the arguments are what the second keeps and the first starts
    * empty.
    */
  private def start(
      settings: StreamSettings,
      now: Long,
      queue: Queue[Pending],
      deadlines: TreeSet[DeadlineKey],
      nextSerial: Long,
      rtoEstimator: RtoEstimator,
      retransmittedAt: Vector[Long],
      stats: StreamStats
  ): SecureStream =
    new SecureStream(
      settings,
      lastAckedSeq = settings.maxSeq,
      nextSeqNo = 0,
      slots = Vector.empty,
      queue = queue,
      queuedCount = queue.length,
      dropped = Set.empty,
      deadlines = deadlines,
      nextSerial = nextSerial,
      rtoEstimator = rtoEstimator,
      rtxAt = NoTime,
      dupAcks = 0,
      recoverSeq = NoRecovery,
      rtxAhead = NoMark,
      dupAcksSinceRtx = 0,
      coveredSentAt = NoTime,
      lastInOrderSeq = settings.maxSeq,
      buffer = Map.empty,
      lastTransmitAt = now,
      idleAckOwed = false,
      retransmittedAt = retransmittedAt,
      reuseBlockedUntil = NoTime,
      stats = stats
    )

  private[stream] final val NoTime = Long.MinValue
  private[stream] final val NoDeadline = Long.MaxValue
  private[stream] final val NoRecovery = -1
  private[stream] final val NoMark = -1

  /** A sent, unacknowledged data segment; `serial` links it to its deadline entry. */
  private[stream] final case class Slot(
      seq: Int,
      serial: Long,
      id: Long,
      payload: Array[Byte],
      deadline: Long,
      firstSentAt: Long,
      lastSentAt: Long,
      transmissions: Int,
      expired: Boolean
  )

  /** A payload waiting for a window slot. */
  private[stream] final case class Pending(serial: Long, id: Long, payload: Array[Byte], deadline: Long)

  /** Orders live payloads by deadline so the earliest is found without scanning the queue. */
  private[stream] final case class DeadlineKey(deadline: Long, serial: Long, id: Long)

  private[stream] object DeadlineKey {
    implicit val ordering: Ordering[DeadlineKey] = (a: DeadlineKey, b: DeadlineKey) => {
      val byDeadline = java.lang.Long.compare(a.deadline, b.deadline)
      if (byDeadline != 0) byDeadline else java.lang.Long.compare(a.serial, b.serial)
    }
  }

}
