package naogateway.gateway.robot

import scala.concurrent.duration._

import naogateway.api.ClockEstimate

/** Settings of the clock estimate: how much robot time the window of keep-alives covers. */
final case class ClockSyncSettings(window: FiniteDuration = ClockSync.DefaultWindow) {
  require(window >= 5.seconds && window <= 1.hour, s"clock-sync.window must be between 5 s and 1 h, is $window")
}

/** The estimate of one robot's clock against the gateway's, from keep-alives alone (nothing is sent to the robot):
  * immutable, one value per robot session, advanced by [[add]].
  *
  * Each keep-alive gives a point (robot time r, gateway receive time g). With the robot's clock a line of the
  * gateway's, g = line(r) + delay, and the delay is never negative, so every point lies on or above the true line and
  * the points of the least delay lie closest to it. The fit is the line below every point of the window that lies
  * highest at the window's mean robot time: the edge of the points' lower convex hull over that mean (a linear
  * programme whose answer is that edge), its slope the drift. The slope is held within [[MaxDriftPpm]], which only a
  * window of few points can exceed.
  *
  * The error bound: the fit's line touches two points, and the error of the line is linear between what their delays
  * make it at each. Those delays are not seen; they are taken as at most a multiple of the `k`-th smallest distance of
  * the window's points above the line (`k` = [[BoundRank]], or half the points while fewer; the factor is
  * [[BoundFactor]]) plus [[ReadingMillis]] for the robot's whole-ms readings. Away from the two points the bound grows
  * with the distance over their span. It is a statistical bound for delays whose least values recur (the jitter of a
  * LAN), not a proof: a link whose every datagram of the window waited long shifts the offset by that wait (see
  * [[ClockEstimate]]).
  *
  * Bounded memory: at most [[MaxSamples]] points within `window` of robot time. A robot clock that goes back by more
  * than a second starts a new session, as a restart does ([[restart]]); a point far below the line (beyond the bound
  * and [[OutlierMarginMillis]]) is set aside as an outlier, and three in a row mean the clock stepped: a new session
  * starts from them. The fit is computed again at most once per [[RefitEvery]] of robot time, or when a point lies
  * below the line, so a keep-alive costs little more than an append.
  */
final class ClockSync private (
    val settings: ClockSyncSettings,
    // The session's first point, subtracted from every point so that the doubles keep their precision.
    anchorRobot: Long,
    anchorGateway: Long,
    // Sorted by robot time, one point per robot ms (the least delay): x = robot ms since the anchor, y = gateway ms
    // since the anchor minus x. Primitive arrays, never written after construction (every change copies): a window of
    // 300 boxed Doubles in two Vectors cost a robot about 12 KiB, these 4.7 KiB.
    xs: Array[Double],
    ys: Array[Double],
    newestRobot: Long,
    fit: Option[ClockSync.Fit],
    suspects: Vector[(Long, Long)],
    /** Points set aside as outliers in this session. */
    val outliers: Long,
    /** Sessions started since this estimator was created (restarts, clock steps). */
    val sessions: Long
) {
  import ClockSync._

  /** Points in the window. */
  def samples: Int = xs.length

  /** The current estimate, anchored at the newest keep-alive; None until the window holds [[MinSamples]] points. */
  def estimate: Option[ClockEstimate] = fit.map { f =>
    val x = (newestRobot - anchorRobot).toDouble
    val gatewayMs = x + f.c + f.s * x
    ClockEstimate(
      robotMillis = newestRobot,
      gatewayNanos = anchorGateway + math.round(gatewayMs * 1e6),
      gatewayPerRobot = 1.0 + f.s,
      errorBoundMillis = f.boundAt(x),
      boundGrowth = f.growth,
      samples = xs.length
    )
  }

  /** The estimator after one keep-alive stamped `robotMillis` by the robot and received at `gatewayNanos`. */
  def add(robotMillis: Long, gatewayNanos: Long): ClockSync =
    if (xs.isEmpty) fresh(robotMillis, gatewayNanos, sessions)
    else if (robotMillis < newestRobot - ClockWentBackMillis) fresh(robotMillis, gatewayNanos, sessions + 1)
    else {
      val x = (robotMillis - anchorRobot).toDouble
      val y = (gatewayNanos - anchorGateway) / 1e6 - x
      fit match {
        case Some(f) if y < f.c + f.s * x - f.boundAt(x) - OutlierMarginMillis =>
          val now = suspects :+ (robotMillis -> gatewayNanos)
          if (now.size >= StepAfter) now.foldLeft(restart)((sync, p) => sync.add(p._1, p._2))
          else copy(suspects = now, outliers = outliers + 1)
        case _ => withPoint(robotMillis, x, y)
      }
    }

  /** A robot time from `RobotHealth.uptimeMs` (32 bits, wraps after about 49.7 days) for a keep-alive without
    * `Status.timestamp`: the reading nearest this session's newest one, so a wrap is no step.
    */
  def unwrap32(uptimeMs: Long): Long =
    if (xs.isEmpty) uptimeMs & 0xffffffffL
    else {
      val low = uptimeMs & 0xffffffffL
      val base = newestRobot & ~0xffffffffL
      Seq(base - (1L << 32), base, base + (1L << 32)).map(_ + low).filter(_ >= 0).minBy(t => math.abs(t - newestRobot))
    }

  /** A new session of the robot (it restarted): everything learnt of the old clock is dropped. */
  def restart: ClockSync =
    new ClockSync(settings, 0L, 0L, NoPoints, NoPoints, 0L, None, Vector.empty, outliers, sessions + 1)

  private def fresh(robotMillis: Long, gatewayNanos: Long, session: Long): ClockSync =
    new ClockSync(settings, robotMillis, gatewayNanos, Array(0.0), Array(0.0), robotMillis, None, Vector.empty,
      outliers, session)

  private def withPoint(robotMillis: Long, x: Double, y: Double): ClockSync = {
    // Keep-alives come in order almost always: an append; a late one is put in its place.
    val i = if (x > xs(xs.length - 1)) xs.length else insertionPoint(x)
    val sameMs = i < xs.length && xs(i) == x
    val newest = math.max(newestRobot, robotMillis)
    val from = (newest - anchorRobot).toDouble - settings.window.toMillis
    // The points kept: those of the window (at most MaxSamples, newest), with the new one in its place.
    val size = if (sameMs) xs.length else xs.length + 1
    def xAt(j: Int): Double = if (sameMs || j < i) xs(j) else if (j == i) x else xs(j - 1)
    var drop = 0
    while (drop < size && xAt(drop) < from) drop += 1
    drop = math.max(drop, size - MaxSamples)
    val x2 = new Array[Double](size - drop)
    val y2 = new Array[Double](size - drop)
    var j = drop
    while (j < size) {
      x2(j - drop) = xAt(j)
      y2(j - drop) =
        if (sameMs) { if (j == i) math.min(y, ys(j)) else ys(j) }
        else if (j < i) ys(j) else if (j == i) y else ys(j - 1)
      j += 1
    }
    val due = fit match {
      case None    => x2.length >= MinSamples
      case Some(f) => y < f.c + f.s * x || x - f.at >= RefitEvery.toMillis || x2.length < MinSamples
    }
    val refit = if (due) fitLine(x2, y2, x) else fit
    new ClockSync(settings, anchorRobot, anchorGateway, x2, y2, newest, refit, Vector.empty, outliers, sessions)
  }

  private def insertionPoint(x: Double): Int = {
    var lo = 0
    var hi = xs.length
    while (lo < hi) {
      val mid = (lo + hi) >>> 1
      if (xs(mid) < x) lo = mid + 1 else hi = mid
    }
    lo
  }

  private def copy(suspects: Vector[(Long, Long)], outliers: Long): ClockSync =
    new ClockSync(settings, anchorRobot, anchorGateway, xs, ys, newestRobot, fit, suspects, outliers, sessions)
}

/** The estimator's constants and its start. */
object ClockSync {

  /** The default window: a minute of keep-alives, 300 at the robot's 200 ms. */
  val DefaultWindow: FiniteDuration = 60.seconds

  /** Points the window holds at most, whatever the keep-alive rate. */
  val MaxSamples: Int = 512

  /** Points before the first estimate. */
  val MinSamples: Int = 10

  /** How much wider the bound is with few points: the factor is 1 + this / the number of points. */
  val SmallSampleWidening: Double = 8.0

  /** The rank of the distance above the line that bounds the touching points' delays (see [[ClockSync]]). */
  val BoundRank: Int = 10

  /** The factor on that distance. */
  val BoundFactor: Double = 2.5

  /** What the robot's whole-ms readings add: each is up to 1 ms behind its clock, and as that cut sweeps along a window
    * it can tilt the fit by up to half as much again.
    */
  val ReadingMillis: Double = 1.5

  /** The largest drift a fit may show; crystals are within about 100 ppm. */
  val MaxDriftPpm: Double = 1000.0

  /** How far below the bound a point must lie to be set aside as an outlier. */
  val OutlierMarginMillis: Double = 20.0

  /** Outliers in a row that mean the robot's clock stepped. */
  val StepAfter: Int = 3

  /** A robot clock going back by more than this starts a new session (the restart rule of docs/protocol.md 6.2). */
  val ClockWentBackMillis: Long = 1000L

  /** Robot time between two fits while no point lies below the line. */
  val RefitEvery: FiniteDuration = 1.second

  /** An estimator with no point yet. */
  def apply(settings: ClockSyncSettings = ClockSyncSettings()): ClockSync =
    new ClockSync(settings, 0L, 0L, NoPoints, NoPoints, 0L, None, Vector.empty, 0L, 0L)

  private val NoPoints: Array[Double] = Array.emptyDoubleArray

  /** The line y = c + s x fitted at robot time `at`; `v1`, `v2` the robot times of the points it touches (equal when
    * the slope was held at the limit), `b` the bound on their delays.
    */
  private final case class Fit(c: Double, s: Double, v1: Double, v2: Double, b: Double, at: Double) {
    private val limited = v2 <= v1

    /** Per ms of robot time away from the touching points. */
    val growth: Double = if (limited) 2 * MaxDriftPpm * 1e-6 else b / (v2 - v1)

    /** The bound at robot time `x`: the delays of both touching points may be anything in [0, b]. */
    def boundAt(x: Double): Double =
      if (limited) b + growth * math.abs(x - v1)
      else {
        val l = (x - v1) / (v2 - v1)
        b * math.max(1.0, math.max(l, 1.0 - l))
      }
  }

  // Reads the arrays only: they are the estimator's, shared with every later ClockSync.
  private def fitLine(px: Array[Double], py: Array[Double], at: Double): Option[Fit] = {
    val n = px.length
    if (n < MinSamples) None
    else {
      // The lower convex hull, by the monotone chain over points sorted by x.
      val hull = new Array[Int](n)
      var h = 0
      var i = 0
      while (i < n) {
        while (h >= 2 && {
            val a = hull(h - 2)
            val b = hull(h - 1)
            (px(b) - px(a)) * (py(i) - py(a)) - (py(b) - py(a)) * (px(i) - px(a)) <= 0
          }) h -= 1
        hull(h) = i
        h += 1
        i += 1
      }
      val mean = px.sum / n
      var e = 0
      while (e < h - 2 && px(hull(e + 1)) < mean) e += 1
      val (p, q) = (hull(e), hull(e + 1))
      val slope = (py(q) - py(p)) / (px(q) - px(p))
      val limit = MaxDriftPpm * 1e-6
      val (c, s, v1, v2) =
        if (math.abs(slope) <= limit) (py(p) - slope * px(p), slope, px(p), px(q))
        else {
          // The supporting line of the held slope touches the one hull point where y - s x is least.
          val s = math.max(-limit, math.min(limit, slope))
          val best = (0 until h).map(hull(_)).minBy(j => py(j) - s * px(j))
          (py(best) - s * px(best), s, px(best), px(best))
        }
      val above = Array.tabulate(n)(j => math.max(0.0, py(j) - c - s * px(j)))
      java.util.Arrays.sort(above)
      // Few points say little about how low the delays go: the bound is widened by SmallSampleWidening / n, which
      // fades as the window fills (x 1.6 at the first estimate's 13 points, x 1.03 at 300).
      val b = BoundFactor * (1.0 + SmallSampleWidening / n) * above(math.min(BoundRank, n / 2)) + ReadingMillis
      Some(Fit(c, s, v1, v2, b, at))
    }
  }
}
