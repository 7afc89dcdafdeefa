package naogateway.wire.stream

import scala.collection.immutable.Queue

import naogateway.wire.WireLimits
import naogateway.wire.stream.SecureStream._

/** One transition, worked out on local variables so a step allocates one new state, not one per field change. */
private[stream] final class SecureStreamWork(s: SecureStream, now: Long) {
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

  /** A receiver holding the next segment m takes the number m + W as new, and that number was last carried by segment m
    * \- (N - W). If that one was sent again within the last round trip, a copy may still be on its way, so m waits
    * until it is gone (the sequence-reuse rule).
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
