package naogateway.wire.stream

import scala.concurrent.duration._

import naogateway.wire.WireLimits

/** Configuration of one secure-stream endpoint (docs/protocol.md §11); both ends of a pair must agree on `window` and
  * `maxSeq`.
  *
  * @param window
  *   how many data segments may be unacknowledged at once (1 = the thesis's stop-and-wait, up to 20 = selective repeat)
  * @param maxSeq
  *   the highest sequence number before the counter wraps to 0; at most 41 so that a segment never starts with the
  *   bytes `00 2A` (FU-Remote) or `RG` (GameController)
  * @param initialRto
  *   the retransmission timeout before the first round-trip sample
  * @param minRto
  *   lower bound of the adaptive retransmission timeout
  * @param maxRto
  *   upper bound of the adaptive retransmission timeout, also the cap of the exponential back-off
  * @param idleAckInterval
  *   how long an endpoint stays silent before it repeats its last ACK once, after data arrived (the idle ACK)
  * @param sendQueueLimit
  *   how many payloads may wait for a free window slot; a send beyond it is refused, never dropped
  * @param honourSkipNotices
  *   whether byte 0 of a pure ACK that lies ahead of the last in-order sequence number is taken as "the sender gave up
  *   on everything up to here". Switch it off for a peer running the thesis firmware: that firmware puts its own,
  *   possibly unacknowledged, sequence number into byte 0 of its pure ACKs, and honouring it would skip data that is
  *   still on its way.
  */
final case class StreamSettings(
    window: Int,
    maxSeq: Int,
    initialRto: FiniteDuration = StreamSettings.DefaultInitialRto,
    minRto: FiniteDuration = StreamSettings.DefaultMinRto,
    maxRto: FiniteDuration = StreamSettings.DefaultMaxRto,
    idleAckInterval: FiniteDuration = StreamSettings.DefaultIdleAckInterval,
    sendQueueLimit: Int = StreamSettings.DefaultSendQueueLimit,
    honourSkipNotices: Boolean = true
) {
  require(
    window >= 1 && window <= StreamSettings.MaxWindow,
    s"window must be between 1 and ${StreamSettings.MaxWindow}, was $window"
  )
  require(
    maxSeq >= 1 && maxSeq < WireLimits.StreamSequenceLimit,
    s"maxSeq must be between 1 and ${WireLimits.StreamSequenceLimit - 1} (so a segment never reads 00 2A or RG), " +
      s"was $maxSeq"
  )
  require(
    2 * window <= maxSeq + 1,
    s"window $window needs at least ${2 * window} sequence numbers (maxSeq >= ${2 * window - 1}) so that old and " +
      s"new segments are never confused, but maxSeq is $maxSeq"
  )
  require(minRto > Duration.Zero, s"minRto must be positive, was $minRto")
  require(maxRto >= minRto, s"maxRto ($maxRto) must not be below minRto ($minRto)")
  require(
    initialRto >= minRto && initialRto <= maxRto,
    s"initialRto ($initialRto) must lie between minRto ($minRto) and maxRto ($maxRto)"
  )
  require(idleAckInterval > Duration.Zero, s"idleAckInterval must be positive, was $idleAckInterval")
  require(sendQueueLimit >= 1, s"sendQueueLimit must be at least 1, was $sendQueueLimit")

  /** The number of distinct sequence numbers, `maxSeq + 1`. */
  def sequenceSpace: Int = maxSeq + 1

  private[stream] val initialRtoNanos: Long = initialRto.toNanos
  private[stream] val minRtoNanos: Long = minRto.toNanos
  private[stream] val maxRtoNanos: Long = maxRto.toNanos
  private[naogateway] val idleAckNanos: Long = idleAckInterval.toNanos
}

/** Defaults and the two standard shapes of the stream. */
object StreamSettings {

  /** The largest window the gateway supports (half of the 42 usable sequence numbers, rounded down to 20). */
  val MaxWindow: Int = 20

  /** The sequence counter of the thesis example firmware runs 0..20. */
  val ThesisMaxSeq: Int = 20

  /** The largest counter that keeps segments apart from FU-Remote and GameController datagrams. */
  val LargestMaxSeq: Int = WireLimits.StreamSequenceLimit - 1

  /** Long enough for a WLAN hop with the module's serial latency, short enough to recover a loss within a second. */
  val DefaultInitialRto: FiniteDuration = 200.millis

  /** Keeps the timer above the scheduling noise of the gateway and the robot's main loop. */
  val DefaultMinRto: FiniteDuration = 20.millis

  /** A link that needs longer than this is better reported as down than waited for. */
  val DefaultMaxRto: FiniteDuration = 2.seconds

  /** Keep-alive period; also bounds how long a lost ACK stays unrecovered. */
  val DefaultIdleAckInterval: FiniteDuration = 200.millis

  /** Bounds memory per stream; callers see refusals long before the gateway's heap is at risk. */
  val DefaultSendQueueLimit: Int = 1024

  /** The thesis protocol: stop-and-wait with sequence numbers 0..20. */
  val thesis: StreamSettings = StreamSettings(window = 1, maxSeq = ThesisMaxSeq)

  /** Selective repeat with `window` segments in flight over the full sequence space 0..41. */
  def selectiveRepeat(window: Int = MaxWindow): StreamSettings =
    StreamSettings(window = window, maxSeq = LargestMaxSeq)
}
