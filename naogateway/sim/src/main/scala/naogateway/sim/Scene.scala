package naogateway.sim

import naogateway.wire.{HaViMo, HaViMoRegion}

/** A robot's place on the field: metres from the centre spot, heading in radians (0 = towards the +x goal). */
final case class Pose(x: Double, y: Double, theta: Double) {

  /** Where a point of the field lies seen from the robot: (ahead, left) in metres. */
  def relative(px: Double, py: Double): (Double, Double) = {
    val dx = px - x
    val dy = py - y
    val c = math.cos(theta)
    val s = math.sin(theta)
    (dx * c + dy * s, -dx * s + dy * c)
  }

  /** The pose after moving for `seconds` with robot-relative velocities. */
  def moved(vx: Double, vy: Double, omega: Double, seconds: Double): Pose = {
    val c = math.cos(theta)
    val s = math.sin(theta)
    Pose(x + (vx * c - vy * s) * seconds, y + (vx * s + vy * c) * seconds, Scene.normalise(theta + omega * seconds))
  }
}

/** The field a simulated robot sees: a ball and two goals (kid-size dimensions). */
final case class Scene(ballX: Double, ballY: Double, fieldLength: Double = 9.0, goalWidth: Double = 2.6) {

  /** Distance from a pose to the ball, in metres. */
  def ballDistance(pose: Pose): Double = math.hypot(ballX - pose.x, ballY - pose.y)
}

/** The regions [[Scene.regions]] gives for a scene seen from a pose with the head at (pan, tilt): a robot that did not
  * move, whose head did not turn and whose ball stayed put sees them again, without projecting anything.
  */
final case class CameraView(scene: Scene, pose: Pose, head: (Double, Double), regions: Vector[HaViMoRegion]) {

  /** Whether this view is what `scene` looks like from `pose` with the head at `head`. */
  def sees(scene: Scene, pose: Pose, head: (Double, Double)): Boolean =
    scene == this.scene && pose == this.pose && head == this.head
}

/** Geometry of the HaViMo2 camera on the robot's head and what it reports for a scene. */
object Scene {
  val BallColour: Int = 1
  val YellowGoalColour: Int = 2
  val BlueGoalColour: Int = 3

  val CameraHeight: Double = 0.35
  val HorizontalFov: Double = 1.0
  val VerticalFov: Double = 0.75
  val BallRadius: Double = 0.05
  val GoalHeight: Double = 0.8

  /** An angle folded into (-pi, pi]. */
  def normalise(angle: Double): Double = {
    val a = angle % (2 * math.Pi)
    if (a > math.Pi) a - 2 * math.Pi else if (a <= -math.Pi) a + 2 * math.Pi else a
  }

  private final case class Box(minX: Double, maxX: Double, minY: Double, maxY: Double)

  /** Image coordinates of a field point at `height`, or None when it is behind the camera. */
  private def project(pose: Pose, pan: Double, tilt: Double, px: Double, py: Double, height: Double) = {
    val (ahead, left) = pose.relative(px, py)
    if (ahead <= 0.01) None
    else {
      val distance = math.hypot(ahead, left)
      val bearing = normalise(math.atan2(left, ahead) - pan)
      val elevation = math.atan2(height - CameraHeight, distance) - tilt
      if (math.abs(bearing) >= math.Pi / 2) None
      else
        Some(
          (
            HaViMo.ImageWidth / 2.0 - bearing / (HorizontalFov / 2) * (HaViMo.ImageWidth / 2.0),
            HaViMo.ImageHeight / 2.0 - elevation / (VerticalFov / 2) * (HaViMo.ImageHeight / 2.0),
            distance
          )
        )
    }
  }

  private def clip(b: Box): Option[Box] = {
    val c = Box(b.minX.max(0), b.maxX.min(HaViMo.ImageWidth - 1.0), b.minY.max(0), b.maxY.min(HaViMo.ImageHeight - 1.0))
    if (c.minX > c.maxX || c.minY > c.maxY) None else Some(c)
  }

  private def region(index: Int, colour: Int, box: Box, fill: Double): HaViMoRegion = {
    val w = box.maxX - box.minX + 1
    val h = box.maxY - box.minY + 1
    val pixels = math.max(1, math.min(0xffff, math.round(w * h * fill).toInt))
    val cx = (box.minX + box.maxX) / 2
    val cy = (box.minY + box.maxY) / 2
    HaViMoRegion(index, colour, pixels, math.round(cx * pixels), math.round(cy * pixels), box.maxX.toInt,
      box.minX.toInt, box.maxY.toInt, box.minY.toInt)
  }

  /** The regions the camera reports for this view: ball first, then the goals in sight (at most 15). */
  def regions(scene: Scene, pose: Pose, pan: Double, tilt: Double): Vector[HaViMoRegion] = {
    val ball = project(pose, pan, tilt, scene.ballX, scene.ballY, BallRadius).flatMap { case (x, y, d) =>
      val angular = math.atan2(BallRadius, d)
      val rx = math.max(1.0, angular / (HorizontalFov / 2) * (HaViMo.ImageWidth / 2.0))
      val ry = math.max(1.0, angular / (VerticalFov / 2) * (HaViMo.ImageHeight / 2.0))
      clip(Box(x - rx, x + rx, y - ry, y + ry)).map(b => (BallColour, b, math.Pi / 4))
    }
    def goal(gx: Double, colour: Int) = {
      // The four corners (both posts, foot and top) must all be in front of the camera; their bounding box is the goal.
      // Loops rather than collections: this runs for every camera frame. Smallest and largest as Seq.min/max take them.
      var seen = 0
      var minX, maxX, minY, maxY = 0.0
      for (side <- Array(-scene.goalWidth / 2, scene.goalWidth / 2); height <- Array(0.0, GoalHeight))
        project(pose, pan, tilt, gx, side, height).foreach { case (px, py, _) =>
          if (seen == 0) { minX = px; maxX = px; minY = py; maxY = py }
          else {
            if (java.lang.Double.compare(minX, px) > 0) minX = px
            if (java.lang.Double.compare(maxX, px) < 0) maxX = px
            if (java.lang.Double.compare(minY, py) > 0) minY = py
            if (java.lang.Double.compare(maxY, py) < 0) maxY = py
          }
          seen += 1
        }
      if (seen < 4) None else clip(Box(minX, maxX, minY, maxY)).map(b => (colour, b, 0.2))
    }
    val seen =
      Vector(ball, goal(scene.fieldLength / 2, YellowGoalColour), goal(-scene.fieldLength / 2, BlueGoalColour)).flatten
    seen.zipWithIndex.take(HaViMo.MaxRegions).map { case ((colour, box, fill), i) => region(i + 1, colour, box, fill) }
  }

  /** The view of `scene` from `pose` with the head at `head`: `last` again when it is that view. */
  def view(last: Option[CameraView], scene: Scene, pose: Pose, head: (Double, Double)): CameraView =
    last.filter(_.sees(scene, pose, head)).getOrElse(CameraView(scene, pose, head,
        regions(scene, pose, head._1, head._2)))

  /** The 32 × 24 grid for the same view: each cell holds the colour of the region covering it and its pixel count. */
  def grid(regions: Seq[HaViMoRegion]): Array[Byte] = {
    val cells = new Array[Byte](HaViMo.GridCells)
    for {
      r <- regions
      cy <- (r.minY / 5) to math.min(HaViMo.GridHeight - 1, r.maxY / 5)
      cx <- (r.minX / 5) to math.min(HaViMo.GridWidth - 1, r.maxX / 5)
    } {
      val overlapX = math.min(r.maxX, cx * 5 + 4) - math.max(r.minX, cx * 5) + 1
      val overlapY = math.min(r.maxY, cy * 5 + 4) - math.max(r.minY, cy * 5) + 1
      val count = math.min(15, math.max(1, overlapX * overlapY * 15 / 25))
      cells(HaViMo.cellIndex(cx, cy)) = ((count << 4) | (r.colour & 0x0f)).toByte
    }
    cells
  }
}
