package naogateway.api

import naogateway.wire.{HaViMoGrid, HaViMoRegion}

/** One HaViMo2 result of one robot. */
sealed trait VisionFrame extends Product with Serializable {
  def robotId: Int
  def frame: Long
}

/** The kinds of HaViMo2 results. */
object VisionFrame {

  /** The regions of one camera frame. */
  final case class Regions(robotId: Int, frame: Long, timestampMs: Option[Long], regions: Vector[HaViMoRegion])
      extends VisionFrame

  /** The 32 × 24 grid of one camera frame. */
  final case class Grid(robotId: Int, frame: Long, timestampMs: Option[Long], grid: HaViMoGrid) extends VisionFrame
}
