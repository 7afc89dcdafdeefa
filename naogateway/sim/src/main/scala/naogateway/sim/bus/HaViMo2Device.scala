package naogateway.sim.bus

import naogateway.wire.{Dynamixel, HaViMo, HaViMoRegion}

/** The emulated HaViMo2 camera on the bus (docs/protocol.md 6.9, the driver's model in docs/firmware.md "The HaViMo2
  * driver"): a capture (instruction CAP_REGION 0x0E or CAP_GRID 0x15, or a write to address 0) takes what the lens sees
  * and answers nothing; while it is processed the camera answers nothing at all (a ping that gets no answer means "not
  * ready yet"); then its table holds the capture's regions, slot i (1-15) at address 16·i, 16 bytes each in the layout
  * of docs/protocol.md 6.5, unused slots zero, and READ_GRID (0x16: address in 16-byte units, length) reads the 768
  * grid cells. Every capture here takes regions and grid. Pure, on the robot's clock (nanoseconds).
  *
  * @param regions
  *   the region buffer of the last finished capture (240 bytes)
  * @param grid
  *   the grid of the last finished capture (768 bytes)
  * @param lens
  *   what the camera sees now: the next capture's regions
  * @param busyUntil
  *   the end of the capture in progress; the camera is silent before it
  * @param captures
  *   captures started since power-up
  */
final case class HaViMo2Device(
    regions: Vector[Byte],
    grid: Vector[Byte],
    lens: Vector[HaViMoRegion],
    busyUntil: Long,
    captures: Long,
    captureNanos: Long
) {
  import HaViMo2Device._

  /** Whether the camera answers at `now` (no capture in progress). */
  def ready(now: Long): Boolean = now >= busyUntil

  /** The camera seeing `view` from now on (the next capture takes it). */
  def seeing(view: Vector[HaViMoRegion]): HaViMo2Device = copy(lens = view)

  /** Reads `length` bytes of the table from `address`, or the error bits of a read past its 256 addresses. */
  def read(address: Int, length: Int): Either[Int, Vector[Int]] =
    if (length < 1 || address + length > 256) Left(Dynamixel.RangeError)
    else
      Right((address until address + length).toVector.map(a =>
          if (a < BufferAddress) 0 else regions(a - BufferAddress) & 0xff))

  /** READ_GRID: `length` cells from cell 16·`block`, or the error bits of a read past the 768 cells. */
  def readGrid(block: Int, length: Int): Either[Int, Vector[Int]] =
    if (length < 1 || block * 16 + length > HaViMo.GridCells) Left(Dynamixel.RangeError)
    else Right(grid.slice(block * 16, block * 16 + length).map(_ & 0xff))

  /** A capture of what the lens sees, started at `now`. */
  def capture(now: Long): HaViMo2Device = {
    val records = HaViMo.encodeRegions(lens.take(HaViMo.MaxRegions).zipWithIndex.map { case (r, i) =>
      r.copy(index = i + 1)
    }).getOrElse(Array.emptyByteArray)
    val buffer = records.toVector ++ Vector.fill(RegionBufferBytes - records.length)(0.toByte)
    copy(regions = buffer, grid = naogateway.sim.Scene.grid(lens).toVector, busyUntil = now + captureNanos,
      captures = captures + 1)
  }
}

/** The camera's instructions, addresses and the emulation's figures. */
object HaViMo2Device {

  /** The HaViMo2's fixed id. */
  val Id: Int = 100

  /** Instructions of its own: capture regions, capture the grid, read the grid. */
  val CapRegion: Int = 0x0e
  val CapGrid: Int = 0x15
  val ReadGrid: Int = 0x16

  /** A write here starts a capture too (the public CM-5x0 examples). */
  val CaptureAddress: Int = 0

  /** Where the region buffer starts: slot i is at 16·i. */
  val BufferAddress: Int = 16

  /** The region buffer: 15 slots of 16 bytes. */
  val RegionBufferBytes: Int = HaViMo.MaxRegions * HaViMo.RegionRecordBytes

  /** How long a capture takes by default (the firmware's busmodel takes as long). */
  val DefaultCaptureNanos: Long = 30000000L

  /** A camera that finished a capture of `view` at power-up. */
  def apply(view: Vector[HaViMoRegion], now: Long, captureNanos: Long = DefaultCaptureNanos): HaViMo2Device =
    HaViMo2Device(Vector.fill(RegionBufferBytes)(0.toByte), Vector.fill(HaViMo.GridCells)(0.toByte), view, now, 0L,
      captureNanos).capture(now).copy(busyUntil = now, captures = 0L)
}
