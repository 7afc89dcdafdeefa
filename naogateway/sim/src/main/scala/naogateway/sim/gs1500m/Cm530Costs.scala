package naogateway.sim.gs1500m

/** The CM-530's measured costs (docs/simulator.md 1.4; thesis §7.3, table 4, figure 15) in unscaled milliseconds, and
  * the same times in simulated nanoseconds multiplied by `timeScale` (1.0 = real time; 0.01 lets a real-time simulation
  * run a hundred times faster while keeping every proportion).
  *
  * The linear fits are the thesis's own coefficients (docs/simulator.md 1.4 rounds them to −0.81 and +0.18): encoding
  * `0.0386·x − 0.8057` ms, serial send `0.0245·x + 0.184` ms, so a 1400-byte message costs ≈ 88 ms in all. A fit below
  * zero (tiny messages) is taken as zero.
  */
final case class Cm530Costs(timeScale: Double = 1.0) {
  require(timeScale > 0.0 && !timeScale.isInfinite, s"timeScale must be positive, is $timeScale")

  import Cm530Costs._

  /** Milliseconds of real CM-530 time as simulated nanoseconds. */
  def nanos(millis: Double): Long = math.round(millis * 1e6 * timeScale)

  /** Encoding an `x`-byte protobuf frame. */
  def encodeNanos(x: Int): Long = nanos(encodeMillis(x))

  /** Pushing an `x`-byte message through `sendWlanDataToCon` to the module. */
  def serialSendNanos(x: Int): Long = nanos(serialSendMillis(x))

  /** Encoding and sending an `x`-byte message. */
  def encodeAndSendNanos(x: Int): Long = nanos(encodeAndSendMillis(x))

  /** Parsing one received message (FU-Remote frame decode, the thesis example code's typical figure). */
  def parseNanos: Long = nanos(ParseMillis)

  /** Reading one text status line from the module (string matching plus echo to the PC), worst case. */
  def statusLineNanos: Long = nanos(StatusLineMillis)

  /** One poll of the serial port that finds nothing or only an OK reply. */
  def emptyPollNanos: Long = nanos(EmptyPollMillis)

  /** Reading the header of one received WLAN message. */
  def messageHeaderNanos: Long = nanos(MessageHeaderMillis)
}

/** The unscaled figures behind [[Cm530Costs]]. */
object Cm530Costs {

  /** Real time. */
  val Real: Cm530Costs = Cm530Costs(1.0)

  /** Slope of the encoding fit, ms per byte. */
  val EncodeSlope: Double = 0.0386

  /** Intercept of the encoding fit, ms. */
  val EncodeIntercept: Double = -0.8057

  /** Slope of the serial send fit, ms per byte. */
  val SendSlope: Double = 0.0245

  /** Intercept of the serial send fit, ms. */
  val SendIntercept: Double = 0.184

  /** Typical parse of one received message (thesis: 5–10 ms in its example code, dominated by output to the PC). */
  val ParseMillis: Double = 5.0

  /** The longest measured read of a status line (table 4: 24.12 ms). */
  val StatusLineMillis: Double = 24.12

  /** Average poll that finds nothing or an OK (table 4: 0.01 ms). */
  val EmptyPollMillis: Double = 0.01

  /** Average read of one WLAN message header (table 4: 0.05 ms). */
  val MessageHeaderMillis: Double = 0.05

  /** Unscaled encoding time of an `x`-byte message, never negative. */
  def encodeMillis(x: Int): Double = math.max(0.0, EncodeSlope * x + EncodeIntercept)

  /** Unscaled serial send time of an `x`-byte message. */
  def serialSendMillis(x: Int): Double = SendSlope * math.max(0, x) + SendIntercept

  /** Unscaled encode-and-send time of an `x`-byte message. */
  def encodeAndSendMillis(x: Int): Double = encodeMillis(x) + serialSendMillis(x)
}
