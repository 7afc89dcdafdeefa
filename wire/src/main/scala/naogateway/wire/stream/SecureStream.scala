package naogateway.wire.stream

import scala.collection.immutable.{Queue, TreeSet}

import naogateway.wire.WireLimits

/** One endpoint of the secure stream (docs/protocol.md §11): reliable, ordered delivery over UDP with the thesis's 2-byte header,
  * as a pure state machine.
  *
  * Every transition takes the current time in nanoseconds (simulated or monotonic; only differences matter) and
  * returns a new state plus the outputs to act on: datagrams to transmit, payloads to deliver, and the fate of the
  * payloads this side sent. The state is immutable and holds no clock, thread or timer: the owner calls [[tick]]
  * when [[nextTimerAt]] has come.
  *
  * Bytes: a payload passed to [[send]] is copied, so the caller may reuse its array; [[receive]] only reads its
  * argument; every array in an output is fresh and belongs to the receiver of the output.
  *
  * ==Rules==
  *   1. A segment is a 2-byte header plus payload. Byte 0 is the sender's own sequence number, byte 1 the ACK: the
  *      sequence number of the last segment received in order from the peer (cumulative). A segment without payload
  *      is a pure ACK; every data segment acknowledges as well (piggybacking).
  *   1. Sequence numbers run from 0 to maxSeq (at most 41; the thesis firmware uses 20) and wrap. The first data
  *      segment has number 0. Before anything has arrived the ACK byte is maxSeq ("the one before 0"), and the
  *      sender's "last acknowledged" starts at maxSeq too.
  *   1. A payload has 1 to 1398 bytes (header plus payload at most 1400). An empty or larger payload is refused when
  *      it is sent, and so is a send while `sendQueueLimit` payloads are waiting. Nothing is dropped silently.
  *   1. The window W (1 to 20, with 2W <= maxSeq + 1) is the number of data segments that may be unacknowledged at
  *      once. At W = 1 segment n is sent only once n - 1 is acknowledged: the thesis protocol.
  *   1. A data segment numbered within [expected, expected + W - 1] is new: the expected one is delivered at once
  *      (followed by any buffered successors), a later one is buffered (only possible at W > 1). One within
  *      [expected - W, expected - 1] is a duplicate and is dropped. Every data segment received, new or duplicate,
  *      is answered at once with an ACK, piggybacked on new data when this side has some to send at that moment,
  *      otherwise as a pure ACK. A pure ACK is never answered, except a skip notice that was acted on (rule 11).
  *   1. An ACK within [last acknowledged, last sent] acknowledges everything up to it. An ACK at most W behind the
  *      last acknowledged one is stale (overtaken on the way): only its ACK byte is disregarded. A datagram that is
  *      shorter than 2 or longer than 1400 bytes, carries a number above maxSeq, a sequence number outside both
  *      ranges of rule 5 or an ACK for something never sent is misbehaving: it is ignored as a whole and counted.
  *      Receiving never throws.
  *   1. One retransmission timer runs for the oldest unacknowledged segment. When it expires only that segment is
  *      sent again and the timeout doubles (up to maxRto). At W > 1 only: two duplicate pure ACKs resend the oldest
  *      segment once per recovery (fast retransmit), and an ACK that advances but does not cover everything sent
  *      before the loss was noticed resends the new oldest segment at once (partial ACK, as in NewReno). A resent
  *      oldest segment is itself taken as lost, and sent again at once, when two more duplicate pure ACKs arrive
  *      after it than the segments ahead of it can explain: those sent after the latest transmission among the
  *      segments the last advancing ACK covered, and before the resend (the link keeps order, so earlier ones were
  *      answered with an older ACK). So only missing segments are sent again, and a lost resend need not wait for
  *      the timer. There is no fast retransmit at W = 1.
  *   1. The timeout adapts as in RFC 6298: SRTT and RTTVAR with alpha 1/8 and beta 1/4, RTO = SRTT + max(1 ms,
  *      4 RTTVAR) kept within [minRto, maxRto], initialRto before the first sample. Karn's rule: an ACK gives a
  *      sample only from the newest segment it covers, and only if that segment was sent once and nothing else the
  *      ACK covers was sent after it. A clean sample ends any back-off; an ACK that acknowledges new data without
  *      giving a sample keeps at most one doubling (see [[RtoEstimator.afterProgress]]).
  *   1. Idle ACK: an endpoint that has received data (or acted on a skip notice) since its last idle ACK, and has
  *      nothing unacknowledged, sends one pure ACK once it has sent nothing for idleAckInterval. It repeats the last
  *      ACK in case that was lost, once: a fresh or reset endpoint, and one whose peer has sent nothing new since,
  *      stays silent. Liveness is the keep-alive's job (protocol.md 6.2), so an idle stream costs the robot's
  *      module buffer nothing.
  *   1. A payload may carry a deadline. Once the deadline is reached, a payload still waiting in the queue is dropped
  *      without using a sequence number, and a sent one is no longer retransmitted; both are reported `Expired`.
  *      Byte 0 of every pure ACK is the sender's "settled" number, the last sequence number such that it and all
  *      earlier ones are acknowledged or expired, announced at most one step past the peer's last ACK. Normally it
  *      equals that ACK and means nothing new. When the oldest unacknowledged segment expires, a pure ACK naming it
  *      goes out at once (a skip notice) and is repeated by the retransmission timer until the peer's ACK has
  *      passed it; several expired segments in a row are announced one per round trip.
  *   1. A receiver that honours skip notices (`honourSkipNotices`, default on) and gets a pure ACK whose byte 0 is
  *      exactly its next expected number treats that segment as expired: it delivers it if it is buffered and
  *      otherwise counts it as skipped, takes it as its last in-order number, delivers the buffered successors and
  *      answers with an ACK. Only the next number is accepted, not the whole window, because byte 0 of an ordinary
  *      pure ACK lags behind the receiver by up to W numbers (its sender has not heard the latest ACKs yet), and by
  *      more when data segments overtake it; with 42 numbers and W = 20 such a lagging ACK falls into
  *      [expected, expected + W - 1] and would skip data that is still on its way. A peer running the thesis
  *      firmware puts its own, possibly unacknowledged, number into byte 0 of pure ACKs, so against it the setting
  *      must be off, and payloads sent to it must carry no deadline: with nobody honouring the notice the stream
  *      would stall behind an expired segment.
  *   1. `Expired` means the sender stopped sending the payload before it was acknowledged. A copy already on its way
  *      may still be delivered before the skip notice arrives, but never after it; no payload is delivered twice or
  *      out of order.
  *   1. Sequence numbers repeat every N = maxSeq + 1 segments, and a receiver that holds segment m accepts the
  *      numbers of m + 1 to m + W as new; the last of them is also the number of segment m + W - N, acknowledged
  *      long ago. A late copy of that old segment would pass for new data. Hence segment m is not sent while segment
  *      m - (N - W) was sent again within the last smoothed round trip (minRto before the first sample). First
  *      transmissions never wait, as a full round trip always lies between them, and at W = 1 the segment in
  *      question is 20 segments old, so the rule does not delay the thesis protocol.
  *   1. Beyond that, as with TCP's maximum segment lifetime, the protocol assumes that no copy of a segment stays
  *      in the network much longer than about one round trip more than the datagrams sent after it. A single WLAN
  *      hop does not hold datagrams that long.
  *   1. `reset` puts the sequence state back to the start (for a peer that restarted, so both ends start afresh).
  *      Unacknowledged and queued payloads are kept and sent again from number 0: at-least-once across a restart.
  */
final class SecureStream private (
    val settings: StreamSettings,
    private val lastAckedSeq: Int,
    private val nextSeqNo: Int,
    private val slots: Vector[SecureStream.Slot],
    private val queue: Queue[SecureStream.Pending],
    private val queuedCount: Int,
    private val dropped: Set[Long],
    private val deadlines: TreeSet[SecureStream.DeadlineKey],
    private val nextSerial: Long,
    val rtoEstimator: RtoEstimator,
    private val rtxAt: Long,
    private val dupAcks: Int,
    private val recoverSeq: Int,
    private val rtxAhead: Int,
    private val dupAcksSinceRtx: Int,
    private val coveredSentAt: Long,
    private val lastInOrderSeq: Int,
    private val buffer: Map[Int, Array[Byte]],
    private val lastTransmitAt: Long,
    private val idleAckOwed: Boolean,
    private val retransmittedAt: Vector[Long],
    private val reuseBlockedUntil: Long,
    val stats: StreamStats
) {
  import SecureStream._

  /** The peer's cumulative ACK: the last own sequence number known to have arrived. */
  def lastAcknowledged: Int = lastAckedSeq

  /** The sequence number the next new data segment will carry. */
  def nextSequence: Int = nextSeqNo

  /** The last sequence number received from the peer in order (the ACK byte this side sends). */
  def lastInOrder: Int = lastInOrderSeq

  /** The last own sequence number such that it and every earlier one is acknowledged or expired; pure ACKs
    * announce it at most one step past the peer's last ACK.
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
      val work = new Work(this, now)
      work.enqueue(payload.clone(), id, deadline.getOrElse(NoDeadline))
      Right(work.result())
    }

  /** Takes one datagram from the peer, header included; malformed or misbehaving ones are counted and ignored. */
  def receive(datagram: Array[Byte], now: Long): Step = {
    val work = new Work(this, now)
    work.receive(datagram)
    work.result()
  }

  /** Handles whatever is due at `now`: expiry, retransmission, keep-alive. Calling it early is harmless. */
  def tick(now: Long): Step = {
    val work = new Work(this, now)
    work.tick()
    work.result()
  }

  /** Starts the sequence state afresh for a peer that restarted, keeping unacknowledged and queued payloads (they
    * are sent again from sequence number 0), the round-trip estimate and the stats.
    */
  def reset(now: Long): Step = {
    val carried: Vector[Pending] =
      slots.filterNot(_.expired).map(s => Pending(s.serial, s.id, s.payload, s.deadline)) ++
        queue.filterNot(p => dropped.contains(p.serial))
    val fresh = new SecureStream(
      settings,
      lastAckedSeq = settings.maxSeq,
      nextSeqNo = 0,
      slots = Vector.empty,
      queue = Queue.from(carried),
      queuedCount = carried.length,
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
    val work = new Work(fresh, now)
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

  /** A fresh endpoint: nothing sent, nothing received, so nothing to send until a payload is offered or data arrives. */
  def initial(settings: StreamSettings, now: Long): SecureStream =
    new SecureStream(
      settings,
      lastAckedSeq = settings.maxSeq,
      nextSeqNo = 0,
      slots = Vector.empty,
      queue = Queue.empty,
      queuedCount = 0,
      dropped = Set.empty,
      deadlines = TreeSet.empty[DeadlineKey],
      nextSerial = 0L,
      rtoEstimator = RtoEstimator.initial(settings),
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
      retransmittedAt = Vector.fill(settings.sequenceSpace)(NoTime),
      reuseBlockedUntil = NoTime,
      stats = StreamStats.zero
    )

  private final val NoTime = Long.MinValue
  private final val NoDeadline = Long.MaxValue
  private final val NoRecovery = -1
  private final val NoMark = -1

  /** A sent, unacknowledged data segment; `serial` links it to its deadline entry. */
  private final case class Slot(
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
  private final case class Pending(serial: Long, id: Long, payload: Array[Byte], deadline: Long)

  /** Orders live payloads by deadline so the earliest is found without scanning the queue. */
  private final case class DeadlineKey(deadline: Long, serial: Long, id: Long)

  private object DeadlineKey {
    implicit val ordering: Ordering[DeadlineKey] = (a: DeadlineKey, b: DeadlineKey) => {
      val byDeadline = java.lang.Long.compare(a.deadline, b.deadline)
      if (byDeadline != 0) byDeadline else java.lang.Long.compare(a.serial, b.serial)
    }
  }

  /** One transition, worked out on local variables so a step allocates one new state, not one per field change. */
  private final class Work(s: SecureStream, now: Long) {
    private val st = s.settings
    private val n = st.sequenceSpace
    private val w = st.window

    private var lastAcked = s.lastAckedSeq
    private var nextSeq = s.nextSeqNo
    private var slots = s.slots
    private var queue = s.queue
    private var queuedCount = s.queuedCount
    private var dropped = s.dropped
    private var deadlines = s.deadlines
    private var nextSerial = s.nextSerial
    private var rto = s.rtoEstimator
    private var rtxAt = s.rtxAt
    private var dupAcks = s.dupAcks
    private var recoverSeq = s.recoverSeq
    // Lost-resend detection. coveredSentAt: the latest transmission among the segments the last advancing ACK
    // covered; the copy that completed that ACK went no later, and the link keeps order, so segments sent before it
    // arrived before it and were answered with an older ACK. rtxAhead: the unacknowledged segments sent after that
    // and before the latest resend of the oldest one; dupAcksSinceRtx: duplicate ACKs counted since that resend. Each
    // segment ahead causes at most one, so more mean the resend itself was lost.
    private var rtxAhead = s.rtxAhead
    private var dupAcksSinceRtx = s.dupAcksSinceRtx
    private var coveredSentAt = s.coveredSentAt
    private var lastInOrder = s.lastInOrderSeq
    private var buffer = s.buffer
    private var lastTransmitAt = s.lastTransmitAt
    private var idleAckOwed = s.idleAckOwed
    private var retransmittedAt = s.retransmittedAt
    private var reuseBlockedUntil = s.reuseBlockedUntil

    private val c0 = s.stats
    private var dataSegmentsSent = c0.dataSegmentsSent
    private var retransmissions = c0.retransmissions
    private var fastRetransmissions = c0.fastRetransmissions
    private var timeouts = c0.timeouts
    private var pureAcksSent = c0.pureAcksSent
    private var segmentsAccepted = c0.segmentsAccepted
    private var delivered = c0.delivered
    private var duplicatesDropped = c0.duplicatesDropped
    private var ignored = c0.ignored
    private var skipped = c0.skipped
    private var acknowledged = c0.acknowledged
    private var expired = c0.expired
    private var lostRetransmissions = c0.lostRetransmissions

    private var outputs = Vector.empty[Output]
    private var sentData = false
    private var sentPureAck = false

    def result(): Step = {
      if (queuedCount == 0 && queue.nonEmpty) {
        queue = Queue.empty
        dropped = Set.empty
      }
      val stats =
        StreamStats(
          dataSegmentsSent,
          retransmissions,
          fastRetransmissions,
          timeouts,
          pureAcksSent,
          segmentsAccepted,
          delivered,
          duplicatesDropped,
          ignored,
          skipped,
          acknowledged,
          expired,
          lostRetransmissions
        )
      val state = new SecureStream(
        st,
        lastAcked,
        nextSeq,
        slots,
        queue,
        queuedCount,
        dropped,
        deadlines,
        nextSerial,
        rto,
        rtxAt,
        dupAcks,
        recoverSeq,
        rtxAhead,
        dupAcksSinceRtx,
        coveredSentAt,
        lastInOrder,
        buffer,
        lastTransmitAt,
        idleAckOwed,
        retransmittedAt,
        reuseBlockedUntil,
        stats
      )
      Step(state, outputs)
    }

    def enqueue(payload: Array[Byte], id: Long, deadline: Long): Unit = {
      expireDue()
      if (deadline <= now) {
        expired += 1
        outputs :+= Expired(id)
      } else {
        val serial = nextSerial
        nextSerial += 1
        queue = queue.enqueue(Pending(serial, id, payload, deadline))
        queuedCount += 1
        if (deadline != NoDeadline) deadlines += DeadlineKey(deadline, serial, id)
        fillWindow()
      }
    }

    def tick(): Unit = {
      expireDue()
      if (rtxAt != NoTime && rtxAt <= now && slots.nonEmpty) {
        timeouts += 1
        rto = rto.backedOff(st)
        recoverSeq = mod(nextSeq - 1)
        dupAcks = 0
        retransmitOldest()
        rtxAt = now + rto.rtoNanos
      }
      fillWindow()
      if (idleAckOwed && slots.isEmpty && !sentData && !sentPureAck && now - lastTransmitAt >= st.idleAckNanos) {
        sendPureAck()
        idleAckOwed = false
      }
    }

    def receive(d: Array[Byte]): Unit = {
      val len = d.length
      if (len < HeaderBytes || len > WireLimits.MaxDatagramBytes) {
        ignored += 1
        expireDue()
      } else {
        val seq = d(0) & 0xff
        val ack = d(1) & 0xff
        if (seq > st.maxSeq || ack > st.maxSeq) {
          ignored += 1
          expireDue()
        } else {
          val isData = len > HeaderBytes
          val ackForward = mod(ack - lastAcked)
          val ackCurrent = ackForward <= slots.length
          val ackStale = !ackCurrent && n - ackForward <= w
          val dataOffset = mod(seq - lastInOrder - 1)
          val dataNew = isData && dataOffset < w
          val dataDuplicate = isData && !dataNew && mod(lastInOrder - seq) < w
          if (!(ackCurrent || ackStale) || (isData && !dataNew && !dataDuplicate)) {
            ignored += 1
            expireDue()
          } else {
            segmentsAccepted += 1
            // The receiving half goes first so that everything sent below already carries the new ACK.
            if (dataNew) acceptData(seq, dataOffset, d)
            else if (dataDuplicate) duplicatesDropped += 1
            val skipNotice = !isData && st.honourSkipNotices && dataOffset == 0
            if (skipNotice) skipNext()
            expireDue()
            if (ackCurrent && ackForward > 0) onAckAdvance(ack, ackForward)
            else if (ackCurrent && !isData) onDuplicateAck()
            fillWindow()
            if (isData || skipNotice) {
              if (!sentData && !sentPureAck) sendPureAck()
              // The answer just sent may be lost: one idle ACK repeats it once the link has been quiet.
              idleAckOwed = true
            }
          }
        }
      }
    }

    private def mod(x: Int): Int = {
      val r = x % n
      if (r < 0) r + n else r
    }

    private def headExpired: Boolean = slots.nonEmpty && slots(0).expired

    /** Byte 0 of a pure ACK: one past the last ACK while the oldest segment has expired, else the last ACK. */
    private def announced: Int = if (headExpired) mod(lastAcked + 1) else lastAcked

    private def expireDue(): Unit =
      if (deadlines.nonEmpty && deadlines.firstKey.deadline <= now) {
        val headExpiredBefore = headExpired
        while (deadlines.nonEmpty && deadlines.firstKey.deadline <= now) {
          val key = deadlines.firstKey
          deadlines -= key
          val i = slots.indexWhere(_.serial == key.serial)
          if (i >= 0) slots = slots.updated(i, slots(i).copy(expired = true))
          else {
            dropped += key.serial
            queuedCount -= 1
          }
          expired += 1
          outputs :+= Expired(key.id)
        }
        if (!headExpiredBefore && headExpired) {
          sendPureAck()
          rtxAt = now + rto.rtoNanos
        }
      }

    /** A receiver holding the next segment m takes the number m + W as new, and that number was last carried by
      * segment m - (N - W). If that one was sent again within the last round trip, a copy may still be on its way,
      * so m waits until it is gone (the sequence-reuse rule).
      */
    private def reuseSafeAt: Long = {
      val lastCopy = retransmittedAt(mod(nextSeq + w))
      if (lastCopy == NoTime) NoTime
      else lastCopy + (if (rto.hasSample) rto.srttNanos else st.minRtoNanos)
    }

    private def fillWindow(): Unit = {
      reuseBlockedUntil = NoTime
      while (slots.length < w && queuedCount > 0 && queue.nonEmpty && reuseBlockedUntil == NoTime) {
        val safeAt = reuseSafeAt
        if (safeAt != NoTime && safeAt > now) reuseBlockedUntil = safeAt
        else takeFromQueue()
      }
    }

    private def takeFromQueue(): Unit = {
      val (p, rest) = queue.dequeue
      queue = rest
      if (dropped.contains(p.serial)) dropped -= p.serial
      else {
        queuedCount -= 1
        slots :+= Slot(nextSeq, p.serial, p.id, p.payload, p.deadline, now, now, 0, expired = false)
        nextSeq = mod(nextSeq + 1)
        transmitSlot(slots.length - 1)
        if (rtxAt == NoTime) rtxAt = now + rto.rtoNanos
      }
    }

    private def transmitSlot(i: Int): Unit = {
      val slot = slots(i)
      val d = new Array[Byte](HeaderBytes + slot.payload.length)
      d(0) = slot.seq.toByte
      d(1) = lastInOrder.toByte
      System.arraycopy(slot.payload, 0, d, HeaderBytes, slot.payload.length)
      outputs :+= Transmit(d)
      dataSegmentsSent += 1
      if (slot.transmissions > 0) {
        retransmissions += 1
        retransmittedAt = retransmittedAt.updated(slot.seq, now)
      }
      slots = slots.updated(i, slot.copy(lastSentAt = now, transmissions = slot.transmissions + 1))
      sentData = true
      lastTransmitAt = now
    }

    private def sendPureAck(): Unit = {
      val d = new Array[Byte](HeaderBytes)
      d(0) = announced.toByte
      d(1) = lastInOrder.toByte
      outputs :+= Transmit(d)
      pureAcksSent += 1
      sentPureAck = true
      lastTransmitAt = now
    }

    /** An expired oldest segment is "resent" as a skip notice: its data must not use the link any more. */
    private def retransmitOldest(): Unit =
      if (slots.nonEmpty) {
        if (!slots(0).expired) transmitSlot(0)
        else if (!sentPureAck) sendPureAck()
        var ahead = 0
        var i = 1
        while (i < slots.length) {
          if (slots(i).lastSentAt >= coveredSentAt) ahead += 1
          i += 1
        }
        rtxAhead = ahead
        dupAcksSinceRtx = 0
      }

    private def deliver(payload: Array[Byte]): Unit = {
      outputs :+= Deliver(payload)
      delivered += 1
    }

    private def acceptData(seq: Int, offset: Int, d: Array[Byte]): Unit =
      if (offset == 0) {
        deliver(java.util.Arrays.copyOfRange(d, HeaderBytes, d.length))
        lastInOrder = seq
        drainBuffer()
      } else if (buffer.contains(seq)) duplicatesDropped += 1
      else buffer = buffer.updated(seq, java.util.Arrays.copyOfRange(d, HeaderBytes, d.length))

    private def drainBuffer(): Unit = {
      var next = mod(lastInOrder + 1)
      var more = buffer.nonEmpty
      while (more) {
        buffer.get(next) match {
          case Some(payload) =>
            deliver(payload)
            buffer -= next
            lastInOrder = next
            next = mod(next + 1)
            more = buffer.nonEmpty
          case None => more = false
        }
      }
    }

    private def skipNext(): Unit = {
      val next = mod(lastInOrder + 1)
      buffer.get(next) match {
        case Some(payload) =>
          deliver(payload)
          buffer -= next
        case None => skipped += 1
      }
      lastInOrder = next
      drainBuffer()
    }

    private def onAckAdvance(ack: Int, count: Int): Unit = {
      val previous = lastAcked
      val newest = slots(count - 1)
      // Karn: only a segment sent once can be timed, and only if nothing else this ACK covers was sent after it
      // (else the ACK may answer that later copy).
      var clean = newest.transmissions == 1
      var coveredAt = NoTime
      var i = 0
      while (i < count) {
        val slot = slots(i)
        if (slot.lastSentAt > newest.firstSentAt) clean = false
        coveredAt = math.max(coveredAt, slot.lastSentAt)
        if (!slot.expired) {
          acknowledged += 1
          outputs :+= Acknowledged(slot.id)
          if (slot.deadline != NoDeadline) deadlines -= DeadlineKey(slot.deadline, slot.serial, slot.id)
        }
        i += 1
      }
      slots = slots.drop(count)
      lastAcked = ack
      dupAcks = 0
      rtxAhead = NoMark
      dupAcksSinceRtx = 0
      coveredSentAt = coveredAt
      rto = if (clean) rto.sample(now - newest.firstSentAt, st) else rto.afterProgress(st)
      val partial = recoverSeq != NoRecovery && {
        val covered = count >= mod(recoverSeq - previous)
        if (covered) recoverSeq = NoRecovery
        !covered
      }
      if (slots.isEmpty) rtxAt = NoTime
      else {
        rtxAt = now + rto.rtoNanos
        if (partial || slots(0).expired) retransmitOldest()
      }
    }

    private def onDuplicateAck(): Unit =
      if (w > 1 && slots.nonEmpty) {
        dupAcks += 1
        if (dupAcks == FastRetransmitThreshold && recoverSeq == NoRecovery) {
          recoverSeq = mod(nextSeq - 1)
          fastRetransmissions += 1
          retransmitOldest()
          rtxAt = now + rto.rtoNanos
        } else if (rtxAhead != NoMark) {
          dupAcksSinceRtx += 1
          // Only the segments that were ahead of the resend can explain a duplicate ACK while it is on its way;
          // FastRetransmitThreshold more than those (a duplicated datagram causes one extra) mean it was lost, so it
          // goes again now instead of after a timeout that a window of queued segments has made long.
          if (dupAcksSinceRtx >= rtxAhead + FastRetransmitThreshold) {
            lostRetransmissions += 1
            retransmitOldest()
            rtxAt = now + rto.rtoNanos
          }
        }
      }
  }
}
