package apps

import naogateway.wire.{HaViMo, HaViMoRegion}

/** The ball follower's control law as a pure function: from one HaViMo2 region frame to head and walk targets. */
object BallFollowerControl {

  /** Colour class of the ball in the HaViMo2 lookup table. */
  val BallColour: Int = 1

  // Camera geometry of the CM-530 robots' HaViMo2 mount (matches the simulated robot's).
  val HorizontalFov: Double = 1.0
  val VerticalFov: Double = 0.75
  val CameraHeight: Double = 0.35
  val BallRadius: Double = 0.05

  /** Close enough to kick: the follower stops here. */
  val ReachedDistance: Double = 0.25

  /** What the follower currently wants. */
  final case class State(pan: Double, tilt: Double, lostFrames: Int, scanDirection: Double, turn: Double,
      reached: Boolean)

  /** Head straight, looking slightly down. */
  val initial: State = State(0.0, -0.3, 0, 1.0, 1.0, reached = false)

  /** The commands for one frame. */
  final case class Targets(pan: Double, tilt: Double, vx: Double, omega: Double, ballDistance: Option[Double])

  private def clamp(v: Double, lo: Double, hi: Double) = math.max(lo, math.min(hi, v))

  /** Where the ball is relative to the body (bearing in radians, distance in metres), seen with the head at pan/tilt.
    */
  def locate(ball: HaViMoRegion, pan: Double, tilt: Double): (Double, Double) = {
    val halfW = HaViMo.ImageWidth / 2.0
    val halfH = HaViMo.ImageHeight / 2.0
    val bearing = pan + (halfW - ball.centreX) / halfW * (HorizontalFov / 2)
    val elevation = tilt + (halfH - ball.centreY) / halfH * (VerticalFov / 2)
    val depression = -elevation
    val distance = if (depression <= 0.02) 5.0 else (CameraHeight - BallRadius) / math.tan(depression)
    (bearing, distance)
  }

  /** One control step for the regions of one frame. */
  def step(state: State, regions: Seq[HaViMoRegion]): (State, Targets) =
    regions.filter(_.colour == BallColour).maxByOption(_.pixels) match {
      case Some(ball) =>
        val (bearing, distance) = locate(ball, state.pan, state.tilt)
        // Keep the ball in the image centre with the head; turn the body towards where the head looks.
        val pan = clamp(bearing, -2.0, 2.0)
        val tilt = clamp(
          state.tilt + (HaViMo.ImageHeight / 2.0 - ball.centreY) / (HaViMo.ImageHeight / 2.0) * (VerticalFov / 2) * 0.7,
          -0.6, 0.5)
        val reached = state.reached || distance < ReachedDistance
        val omega = if (reached) 0.0 else clamp(1.5 * bearing, -1.0, 1.0)
        val vx = if (reached) 0.0
        else if (math.abs(bearing) > 0.6) 0.0 else clamp(0.6 * (distance - ReachedDistance + 0.1), 0.05, 0.3)
        (State(pan, tilt, 0, state.scanDirection, if (bearing < 0) -1.0 else 1.0, reached),
          Targets(pan, tilt, vx, omega, Some(distance)))
      case None =>
        // Lost: sweep the head, and turn the body steadily towards where the ball was last seen.
        val lost = state.lostFrames + 1
        val next = state.pan + 0.15 * state.scanDirection
        val direction = if (math.abs(next) > 1.6) -state.scanDirection else state.scanDirection
        val s = State(clamp(next, -1.6, 1.6), -0.3, lost, direction, state.turn, state.reached && lost < 10)
        (s, Targets(s.pan, s.tilt, 0.0, if (lost > 5 && !s.reached) 0.5 * state.turn else 0.0, None))
    }
}
