package naogateway.wire

import java.nio.{ByteBuffer, ByteOrder}

/** One HaViMo2 region (docs/protocol.md 6.5): colour class, pixel count, coordinate sums and bounding box in the 160 ×
  * 120 image.
  */
final case class HaViMoRegion(
    index: Int,
    colour: Int,
    pixels: Int,
    sumX: Long,
    sumY: Long,
    maxX: Int,
    minX: Int,
    maxY: Int,
    minY: Int
) {

  /** Centre of mass, x, in pixels. */
  def centreX: Double = if (pixels == 0) 0.0 else sumX.toDouble / pixels

  /** Centre of mass, y, in pixels. */
  def centreY: Double = if (pixels == 0) 0.0 else sumY.toDouble / pixels
}

/** One HaViMo2 grid frame: 32 × 24 cells, each a colour class (low nibble) and a pixel count 0-15 (high nibble). */
final case class HaViMoGrid(cells: Vector[Byte]) {
  require(cells.length == HaViMo.GridCells, s"a grid has ${HaViMo.GridCells} cells, not ${cells.length}")

  /** Colour class of cell (x, y). */
  def colour(x: Int, y: Int): Int = cells(HaViMo.cellIndex(x, y)) & 0x0f

  /** Number of pixels (0-15) of that colour in cell (x, y). */
  def count(x: Int, y: Int): Int = (cells(HaViMo.cellIndex(x, y)) >> 4) & 0x0f
}

/** Why HaViMo2 bytes are refused. */
final case class HaViMoError(describe: String)

/** Codecs of the HaViMo2 camera's own byte layouts (docs/protocol.md 6.5). */
object HaViMo {
  val ImageWidth: Int = 160
  val ImageHeight: Int = 120
  val MaxRegions: Int = 15
  val RegionRecordBytes: Int = 16
  val GridWidth: Int = 32
  val GridHeight: Int = 24
  val GridCells: Int = GridWidth * GridHeight
  val MaxFramesPerSecond: Int = 19

  /** Index of cell (x, y) in a grid's 768 bytes. */
  def cellIndex(x: Int, y: Int): Int = {
    require(x >= 0 && x < GridWidth && y >= 0 && y < GridHeight, s"cell ($x, $y) is outside the 32 × 24 grid")
    x + GridWidth * y
  }

  /** Packs regions as 16-byte little-endian records; slots with index 0 are unused and left out. */
  def encodeRegions(regions: Seq[HaViMoRegion]): Either[HaViMoError, Array[Byte]] = {
    val used = regions.filter(_.index != 0)
    if (used.length > MaxRegions) Left(HaViMoError(s"${used.length} regions, the camera reports at most $MaxRegions"))
    else
      used.find(r => !fits(r)).map(r => HaViMoError(s"region field out of range: $r")).toLeft {
        val buffer = ByteBuffer.allocate(used.length * RegionRecordBytes).order(ByteOrder.LITTLE_ENDIAN)
        used.foreach { r =>
          buffer.put(r.index.toByte).put(r.colour.toByte).putShort(r.pixels.toShort)
          buffer.putInt(r.sumX.toInt).putInt(r.sumY.toInt)
          buffer.put(r.maxX.toByte).put(r.minX.toByte).put(r.maxY.toByte).put(r.minY.toByte)
        }
        buffer.array()
      }
  }

  /** Reads 16-byte records; unused slots (index 0) are skipped; never throws. */
  def decodeRegions(bytes: Array[Byte]): Either[HaViMoError, Vector[HaViMoRegion]] =
    if (bytes.length % RegionRecordBytes != 0)
      Left(HaViMoError(s"${bytes.length} bytes is not a whole number of $RegionRecordBytes-byte region records"))
    else if (bytes.length / RegionRecordBytes > MaxRegions)
      Left(HaViMoError(s"${bytes.length / RegionRecordBytes} region records, the camera reports at most $MaxRegions"))
    else {
      val buffer = ByteBuffer.wrap(bytes).order(ByteOrder.LITTLE_ENDIAN)
      val regions = Vector.newBuilder[HaViMoRegion]
      while (buffer.hasRemaining) {
        val index = buffer.get() & 0xff
        val colour = buffer.get() & 0xff
        val pixels = buffer.getShort() & 0xffff
        val sumX = buffer.getInt() & 0xffffffffL
        val sumY = buffer.getInt() & 0xffffffffL
        val region = HaViMoRegion(index, colour, pixels, sumX, sumY, buffer.get() & 0xff, buffer.get() & 0xff,
          buffer.get() & 0xff, buffer.get() & 0xff)
        if (index != 0) regions += region
      }
      Right(regions.result())
    }

  /** Reads a grid frame's 768 cells. */
  def decodeGrid(bytes: Array[Byte]): Either[HaViMoError, HaViMoGrid] =
    if (bytes.length != GridCells) Left(HaViMoError(s"a grid has $GridCells cells, got ${bytes.length} bytes"))
    else Right(HaViMoGrid(bytes.toVector))

  private def fits(r: HaViMoRegion): Boolean = {
    def byte(v: Int) = v >= 0 && v <= 0xff
    byte(r.index) && byte(r.colour) && r.pixels >= 0 && r.pixels <= 0xffff && r.sumX >= 0 && r.sumX <= 0xffffffffL &&
    r.sumY >= 0 && r.sumY <= 0xffffffffL && byte(r.maxX) && byte(r.minX) && byte(r.maxY) && byte(r.minY)
  }
}
