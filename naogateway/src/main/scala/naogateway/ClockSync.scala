package naogateway

import scala.concurrent.duration._

/**
 * What the gateway knows of one robot's clock: when (on the gateway's clock) the robot's clock read `robotMillis`, how
 * fast it runs, and how far off that may be.
 *
 * The gateway's clock is its JVM's `System.nanoTime`, the base of `RobotSnapshot.receivedAtNanos`. One-way observation
 * cannot tell a constant part of the link's delay from an offset: the estimate places a robot reading at the moment
 * its fastest keep-alives would have been received, so the common least delay of the link (on loopback well under
 * 1 ms, on a base station's WiFi a few ms) is inside the offset and outside the bound.
 *
 * @param robotMillis the reading the estimate is anchored at (the newest keep-alive's robot time)
 * @param gatewayNanos when the robot's clock read `robotMillis`, on the gateway's clock
 * @param gatewayPerRobot gateway time per robot time (1.0: the clocks run alike)
 * @param errorBoundMillis how far `gatewayNanos` may be from the truth, in ms
 * @param boundGrowth how much the bound grows per ms of robot time away from `robotMillis`
 * @param samples keep-alives in the window the estimate rests on
 */
final case class ClockEstimate(
    robotMillis: Long,
    gatewayNanos: Long,
    gatewayPerRobot: Double,
    errorBoundMillis: Double,
    boundGrowth: Double,
    samples: Int
) {

  /** How much faster the robot's clock runs than the gateway's, in parts per million (negative: slower). */
  def driftPpm: Double = (1.0 / gatewayPerRobot - 1.0) * 1e6

  /** When the robot's clock read `robotTime` (ms), on the gateway's clock (`System.nanoTime` of the gateway's JVM). */
  def toGatewayNanos(robotTime: Long): Long =
    gatewayNanos + math.round((robotTime - robotMillis).toDouble * gatewayPerRobot * 1e6)

  /** The error bound of [[toGatewayNanos]] at `robotTime`, in ms. */
  def errorBoundAt(robotTime: Long): Double = errorBoundMillis + boundGrowth * math.abs((robotTime - robotMillis).toDouble)
}

/** Settings of the clock estimate: how much robot time the window of keep-alives covers. */
final case class ClockSyncSettings(window: FiniteDuration = ClockSync.DefaultWindow) {
  require(window >= 5.seconds && window <= 1.hour, s"clock-sync.window must be between 5 s and 1 h, is $window")
}

/**
 * The estimate of one robot's clock against the gateway's, from keep-alives alone (nothing is sent to the robot):
 * immutable, one value per robot session, advanced by [[add]].
 *
 * Each keep-alive gives a point (robot time r, gateway receive time g). With the robot's clock a line of the gateway's,
 * g = line(r) + delay, and the delay is never negative, so every point lies on or above the true line and the points
 * of the least delay lie closest to it. The fit is the line below every point of the window that lies highest at the
 * window's mean robot time: the edge of the points' lower convex hull over that mean (a linear programme whose answer
 * is that edge), its slope the drift. The slope is held within [[MaxDriftPpm]], which only a window of few points
 * can exceed.
 *
 * The error bound: the fit's line touches two points, and the error of the line is linear between what their delays
 * make it at each. Those delays are not seen; they are taken as at most a multiple of the `k`-th smallest distance of the
 * window's points above the line (`k` = [[BoundRank]], or half the points while fewer; the factor is
 * [[BoundFactor]]) plus [[ReadingMillis]] for the robot's whole-ms readings. Away from the two points the bound grows with the distance over their
 * span. It is a statistical bound for delays whose least values recur (the jitter of a LAN), not a proof: a link whose
 * every datagram of the window waited long shifts the offset by that wait (see [[ClockEstimate]]).
 *
 * Bounded memory: at most [[MaxSamples]] points within `window` of robot time. A robot clock that goes back by more
 * than a second starts a new session, as a restart does ([[restart]]); a point far below the line (beyond the bound
 * and [[OutlierMarginMillis]]) is set aside as an outlier, and three in a row mean the clock stepped: a new session
 * starts from them. The fit is computed again at most once per [[RefitEvery]] of robot time, or when a point lies below
 * the line, so a keep-alive costs little more than an append.
 */
final class ClockSync private (
    val settings: ClockSyncSettings,
    // The session's first point, subtracted from every point so that the doubles keep their precision.
    anchorRobot: Long,
    anchorGateway: Long,
    // Sorted by robot time, one point per robot ms (the least delay): x = robot ms since the anchor, y = gateway ms
    // since the anchor minus x.
    xs: Vector[Double],
    ys: Vector[Double],
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
  def samples: Int = xs.size

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
      samples = xs.size
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

  /**
   * A robot time from `RobotHealth.uptimeMs` (32 bits, wraps after about 49.7 days) for a keep-alive without
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
    new ClockSync(settings, 0L, 0L, Vector.empty, Vector.empty, 0L, None, Vector.empty, outliers, sessions + 1)

  private def fresh(robotMillis: Long, gatewayNanos: Long, session: Long): ClockSync =
    new ClockSync(settings, robotMillis, gatewayNanos, Vector(0.0), Vector(0.0), robotMillis, None, Vector.empty,
      outliers, session)

  private def withPoint(robotMillis: Long, x: Double, y: Double): ClockSync = {
    // Keep-alives come in order almost always: an append; a late one is put in its place.
    val i = if (x > xs.last) xs.size else insertionPoint(x)
    val (x1, y1) =
      if (i < xs.size && xs(i) == x) (xs, if (y < ys(i)) ys.updated(i, y) else ys)
      else if (i == xs.size) (xs :+ x, ys :+ y)
      else (xs.patch(i, Seq(x), 0), ys.patch(i, Seq(y), 0))
    val newest = math.max(newestRobot, robotMillis)
    val from = (newest - anchorRobot).toDouble - settings.window.toMillis
    val drop = math.max(x1.indexWhere(_ >= from) match { case -1 => x1.size; case n => n }, x1.size - MaxSamples)
    val (x2, y2) = (x1.drop(drop), y1.drop(drop))
    val due = fit match {
      case None    => x2.size >= MinSamples
      case Some(f) => y < f.c + f.s * x || x - f.at >= RefitEvery.toMillis || x2.size < MinSamples
    }
    val refit = if (due) fitLine(x2, y2, x) else fit
    new ClockSync(settings, anchorRobot, anchorGateway, x2, y2, newest, refit, Vector.empty, outliers, sessions)
  }

  private def insertionPoint(x: Double): Int = {
    var lo = 0
    var hi = xs.size
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

  /**
   * What the robot's whole-ms readings add: each is up to 1 ms behind its clock, and as that cut sweeps along a window
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
    new ClockSync(settings, 0L, 0L, Vector.empty, Vector.empty, 0L, None, Vector.empty, 0L, 0L)

  /**
   * The line y = c + s x fitted at robot time `at`; `v1`, `v2` the robot times of the points it touches (equal when
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

  private def fitLine(xs: Vector[Double], ys: Vector[Double], at: Double): Option[Fit] = {
    val n = xs.size
    if (n < MinSamples) None
    else {
      val px = xs.toArray
      val py = ys.toArray
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
