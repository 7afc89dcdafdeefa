package naogateway.wire.stream

/** The adaptive retransmission timeout of RFC 6298, in nanoseconds, as an immutable value.
  *
  * `srttNanos` and `rttvarNanos` are the smoothed round-trip time and its variation (both 0 before the first sample);
  * `rtoNanos` is the timeout in force, including any back-off.
  */
final case class RtoEstimator(srttNanos: Long, rttvarNanos: Long, rtoNanos: Long, samples: Long) {

  /** Whether at least one round-trip sample has been taken. */
  def hasSample: Boolean = samples > 0

  /** Takes one round-trip sample (the caller applies Karn's rule: never from a retransmitted segment).
    *
    * The first sample sets SRTT = R and RTTVAR = R/2; later ones use alpha = 1/8 and beta = 1/4. The new RTO is SRTT +
    * max(G, 4 * RTTVAR) within the configured bounds, which also ends any back-off.
    */
  def sample(rttNanos: Long, settings: StreamSettings): RtoEstimator = {
    val r = math.max(0L, rttNanos)
    val (srtt, rttvar) =
      if (!hasSample) (r, r / 2)
      else {
        val deviation = math.abs(srttNanos - r)
        (srttNanos - srttNanos / 8 + r / 8, rttvarNanos - rttvarNanos / 4 + deviation / 4)
      }
    RtoEstimator(srtt, rttvar, RtoEstimator.fromEstimate(srtt, rttvar, settings), samples + 1)
  }

  /** The timeout after an ACK that acknowledged new data but gave no sample (Karn): at most one doubling of the
    * back-off is kept.
    *
    * Keeping one doubling until a clean sample arrives stops a too-short timeout from firing again and again when the
    * round trip has grown (the reason for Karn's back-off). Keeping all of them would let the timeout climb to maxRto
    * and stay there under heavy loss, where clean samples are rare: at 30 % loss each way a segment and its ACK both
    * arrive only half of the time, so the expected back-off grows without bound.
    */
  def afterProgress(settings: StreamSettings): RtoEstimator = {
    val base = if (hasSample) RtoEstimator.fromEstimate(srttNanos, rttvarNanos, settings) else settings.initialRtoNanos
    copy(rtoNanos = math.min(rtoNanos, math.min(settings.maxRtoNanos, 2 * base)))
  }

  /** Doubles the timeout after it expired, capped at `maxRto` (RFC 6298 §5.5). */
  def backedOff(settings: StreamSettings): RtoEstimator =
    copy(rtoNanos = math.min(settings.maxRtoNanos, if (rtoNanos > Long.MaxValue / 2) Long.MaxValue else rtoNanos * 2))
}

/** Construction of the estimator. */
object RtoEstimator {

  /** The clock granularity G of RFC 6298: the floor of the variance term, 1 ms. */
  val ClockGranularityNanos: Long = 1000000L

  /** The estimator before any sample: the RTO is `initialRto`. */
  def initial(settings: StreamSettings): RtoEstimator = RtoEstimator(0L, 0L, settings.initialRtoNanos, 0L)

  private def fromEstimate(srtt: Long, rttvar: Long, settings: StreamSettings): Long =
    math.max(settings.minRtoNanos, math.min(settings.maxRtoNanos, srtt + math.max(ClockGranularityNanos, 4 * rttvar)))
}
