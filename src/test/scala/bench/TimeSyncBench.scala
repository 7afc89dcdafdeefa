package bench

import scala.collection.immutable.ListMap
import scala.concurrent.duration._

import naogateway.api.ClockEstimate
import naogateway.gateway.robot.ClockSync
import naogateway.sim.RobotClock
import naogateway.sim.network.{Decision, Direction, Impairment, ImpairmentModel}

/** The gateway's estimate of robots' clocks from keep-alives alone (`naogateway.gateway.robot.ClockSync`), against
  * simulated robot clocks of known offset and drift ([[RobotClock]]), their keep-alives passing the lossy network's
  * impairment model (20 % loss, 0-20 ms jitter, the `LossyNetwork`'s own decision function) in simulated time:
  * [[Robots]] robots, each with a random drift within ±200 ppm and offset, keep-alives every 200 ms for [[Minutes]]
  * minutes, the robot's send slot itself 0-2 ms late (its main loop).
  *
  *   - `timesync_error_ms_p95`: the 95th percentile of |estimate − truth| over every estimate after each robot's first
  *     30 s (the moment the robot's clock read the newest keep-alive's timestamp, on the gateway's clock).
  *   - `timesync_converge_s`: median over the robots of the time from the first keep-alive to the first estimate that
  *     is within its own bound and within 5 ms of the truth.
  *   - `timesync_bound_converge_s`: median time until the estimate's own bound is at most 5 ms.
  *   - `timesync_bound_misses`: estimates whose error exceeded their own bound (0 expected).
  *
  * Simulated time, because the figure is the estimator's against the network model, not the machine's speed: the
  * loopback path adds well under a millisecond (sim's ClockSyncIntegrationSpec runs the same over real sockets).
  */
object TimeSyncBench extends Benchmark {
  val name = "timesync"

  private val Robots = 50
  private val Minutes = 10
  private val Goal = 5.0
  private val Network = Impairment(loss = 0.2, jitter = 20.millis)

  private final case class Robot(clock: RobotClock, bootNanos: Long) {
    def reading(t: Long): Long = clock.millisAt(t - bootNanos)
    def truth(r: Long): Double = bootNanos + clock.sinceBootNanosOf(r)
  }

  def run(): ListMap[String, Double] = {
    val random = new scala.util.Random(14)
    val results = (0 until Robots).map { i =>
      val robot = Robot(RobotClock((random.nextInt(3600000)).millis, random.nextDouble() * 400 - 200),
        -random.nextLong(3600000000000L))
      var rng = ImpairmentModel.stream(14, i, Direction.Uplink)
      var sync = ClockSync()
      val t0 = random.nextLong(200000000L)
      var errors = Vector.empty[Double]
      var converged, boundConverged = Double.NaN
      var misses = 0
      var t = t0
      val end = t0 + Minutes * 60L * 1000000000L
      while (t < end) {
        val sent = t + random.nextLong(2000000L)
        val r = robot.reading(sent)
        val (decision, next) = ImpairmentModel.decide(Network, rng)
        rng = next
        decision match {
          case Decision.Deliver(delays, _) =>
            sync = sync.add(r, sent + delays.head.toNanos)
            sync.estimate.foreach { e: ClockEstimate =>
              val error = math.abs(e.gatewayNanos - robot.truth(e.robotMillis)) / 1e6
              val since = (sent - t0) / 1e9
              if (error > e.errorBoundMillis) misses += 1
              if (converged.isNaN && error <= e.errorBoundMillis && error <= Goal) converged = since
              if (boundConverged.isNaN && e.errorBoundMillis <= Goal) boundConverged = since
              if (since >= 30) errors :+= error
            }
          case Decision.Drop(_) => ()
        }
        t += 200000000L
      }
      (errors, converged, boundConverged, misses)
    }
    val errors = results.flatMap(_._1).sorted
    def median(v: Seq[Double]) = { val s = v.sorted; s(s.size / 2) }
    val p95 = errors((errors.size * 0.95).toInt)
    val converge = median(results.map(_._2).map(c => if (c.isNaN) Double.PositiveInfinity else c))
    val boundConverge = median(results.map(_._3).map(c => if (c.isNaN) Double.PositiveInfinity else c))
    val misses = results.map(_._4).sum
    println(
      f"timesync: $Robots robots x $Minutes min at 20 %% loss, 0-20 ms jitter: error p50 ${errors(errors.size / 2)}%.2f ms, " +
        f"p95 $p95%.2f ms, max ${errors.last}%.2f ms; converged (median) $converge%.1f s, bound <= 5 ms after $boundConverge%.1f s; " +
        s"$misses of ${errors.size} estimates outside their bound (${ClockSync.DefaultWindow.toSeconds} s window)")
    ListMap(
      "timesync_error_ms_p95" -> p95,
      "timesync_converge_s" -> converge,
      "timesync_bound_converge_s" -> boundConverge,
      "timesync_bound_misses" -> misses.toDouble
    )
  }
}
