package naogateway.sim.bus

import naogateway.wire.{Dynamixel, HaViMo, HaViMoRegion}

/** The emulated HaViMo2 camera on the bus (docs/protocol.md 6.9, the driver's model in docs/firmware.md "The HaViMo2
  * driver"): a capture (instruction CAP_REGION 0x0E or CAP_GRID 0x15, or a write to address 0) takes what the lens sees
  * and answers nothing; while it is processed the camera answers nothing at all (a ping that gets no answer means "not
  * ready yet"); then its table holds the capture's regions, slot i (1-15) at address 16·i, 16 bytes each in the layout
  * of docs/protocol.md 6.5, unused slots zero, and READ_GRID (0x16: address in 16-byte units, length) reads the 768
  * grid cells. Every capture here takes regions and grid. Pure, on the robot's clock (nanoseconds).
  *
  * @param captured
  *   what the last finished capture took: its region buffer (240 bytes) and grid (768 cells)
  * @param lens
  *   what the camera sees now: the next capture's regions
  * @param busyUntil
  *   the end of the capture in progress; the camera is silent before it
  * @param captures
  *   captures started since power-up
  */
final case class HaViMo2Device(
    captured: HaViMo2Device.Capture,
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
    else if (address >= 0) Right(captured.table.slice(address, address + length))
    else Right(Vector.tabulate(length)(i => if (address + i < 0) 0 else captured.table(address + i)))

  /** READ_GRID: `length` cells from cell 16·`block`, or the error bits of a read past the 768 cells. */
  def readGrid(block: Int, length: Int): Either[Int, Vector[Int]] =
    if (length < 1 || block * 16 + length > HaViMo.GridCells) Left(Dynamixel.RangeError)
    else Right(captured.cells.slice(block * 16, block * 16 + length))

  /** A capture of what the lens sees, started at `now`. */
  def capture(now: Long): HaViMo2Device =
    // A view like the last one's makes the same table: the buffers already made are kept.
    copy(captured = if ((captured.view eq lens) || captured.view == lens) captured else Capture(lens),
      busyUntil = now + captureNanos,
      captures = captures + 1)
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
    HaViMo2Device(Capture(view), view, now, 0L, captureNanos)

  /** One capture of `view`: the table's region buffer and the grid it makes, each made once, when first read. */
  final case class Capture(view: Vector[HaViMoRegion]) {

    /** The region buffer: the first 15 regions' records in slots 1-15 (indices renumbered), unused slots zero. */
    lazy val regionBuffer: Array[Byte] = {
      val records = HaViMo.encodeRegions(view.take(HaViMo.MaxRegions).zipWithIndex.map { case (r, i) =>
        r.copy(index = i + 1)
      }).getOrElse(Array.emptyByteArray)
      java.util.Arrays.copyOf(records, RegionBufferBytes)
    }

    /** The 768 grid cells. */
    lazy val grid: Array[Byte] = naogateway.sim.Scene.grid(view)

    /** The table as reads find it: addresses 0-15 zero (model number 0 included), the region buffer from 16. */
    lazy val table: Vector[Int] = Vector.fill(BufferAddress)(0) ++ regionBuffer.iterator.map(_ & 0xff)

    /** The grid cells as READ_GRID finds them. */
    lazy val cells: Vector[Int] = grid.iterator.map(_ & 0xff).toVector
  }
}
