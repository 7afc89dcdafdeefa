package naogateway.wire.stream

/** Running totals of one secure-stream endpoint, for link statistics and tests; they survive `reset`.
  *
  * @param dataSegmentsSent
  *   data segments handed to the link, first transmissions and retransmissions
  * @param retransmissions
  *   data segments sent again (after a timeout, a fast retransmit or a partial ACK)
  * @param fastRetransmissions
  *   recoveries started by two duplicate ACKs (never at window 1)
  * @param timeouts
  *   expiries of the retransmission timer
  * @param pureAcksSent
  *   header-only segments: answers, keep-alives and skip notices
  * @param segmentsAccepted
  *   received segments that made sense (new data, duplicates and ACKs)
  * @param delivered
  *   payloads handed to the application, in order
  * @param duplicatesDropped
  *   data segments received again and not delivered again
  * @param ignored
  *   malformed or misbehaving datagrams (too short or long, a number above maxSeq, a sequence number outside both
  *   acceptance ranges, an ACK for something never sent)
  * @param skipped
  *   missing segments the receiver stepped over because the peer's skip notice said they had expired
  * @param acknowledged
  *   own payloads the peer acknowledged
  * @param expired
  *   own payloads given up because their deadline passed
  * @param lostRetransmissions
  *   resends of the oldest segment found lost by counting duplicate ACKs, and sent again before the timer expired
  *   (never at window 1)
  */
final case class StreamStats(
    dataSegmentsSent: Long,
    retransmissions: Long,
    fastRetransmissions: Long,
    timeouts: Long,
    pureAcksSent: Long,
    segmentsAccepted: Long,
    delivered: Long,
    duplicatesDropped: Long,
    ignored: Long,
    skipped: Long,
    acknowledged: Long,
    expired: Long,
    lostRetransmissions: Long
) {

  /** Every datagram this endpoint sent. */
  def datagramsSent: Long = dataSegmentsSent + pureAcksSent
}

/** The starting totals. */
object StreamStats {

  /** All totals zero. */
  val zero: StreamStats = StreamStats(0L, 0L, 0L, 0L, 0L, 0L, 0L, 0L, 0L, 0L, 0L, 0L, 0L)
}
