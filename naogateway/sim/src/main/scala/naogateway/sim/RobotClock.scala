package naogateway.sim

import scala.concurrent.duration._

/** A simulated robot's own clock, the one its keep-alives' `Status.timestamp` (and `RobotHealth.uptimeMs`, debug data
  * and camera frames) read: whole milliseconds since power-up, starting at `offset` and running `driftPpm` parts per
  * million fast (negative: slow) against the simulator's clock (`System.nanoTime`). Tests that know it know the truth a
  * clock estimate is checked against ([[RobotView.gatewayNanosOf]]). The default is today's exact uptime clock.
  *
  * @param offset
  *   the reading at power-up (and after every restart): as if the clock had run before the firmware started
  * @param driftPpm
  *   how much faster the clock runs than real time, in parts per million; within ±10000
  */
final case class RobotClock(offset: FiniteDuration = Duration.Zero, driftPpm: Double = 0.0) {
  require(offset >= Duration.Zero, s"a robot clock starts at a reading of at least 0, not $offset")
  require(math.abs(driftPpm) <= 10000.0, s"a robot clock's drift must be within 10000 ppm, is $driftPpm")

  private val rate = 1.0 + driftPpm * 1e-6

  /** The clock's reading `sinceBootNanos` after power-up: cut to whole ms, as a counter of ms ticks reads. */
  def millisAt(sinceBootNanos: Long): Long =
    offset.toMillis + math.floor(math.max(0L, sinceBootNanos) * rate / 1e6).toLong

  /** How long after power-up the clock read `millis` exactly, in ns. */
  def sinceBootNanosOf(millis: Long): Double = (millis - offset.toMillis) * 1e6 / rate
}

/** Clocks of simulated robots. */
object RobotClock {

  /** No offset, no drift: the reading is the uptime. */
  val Exact: RobotClock = RobotClock()
}
