package naogateway.sim.bus

import naogateway.wire.{Dynamixel, HaViMo, HaViMoRegion}

/** The emulated HaViMo2 camera on the bus (the project's model of it, docs/protocol.md 6.9): a write to address 0
  * starts a capture of what the lens sees; while it is processed the camera answers nothing (a ping that gets no answer
  * means "not ready yet"); then the region buffer holds the capture's regions, slot i (1-15) at address 16·i, 16 bytes
  * each in the layout of docs/protocol.md 6.5, unused slots zero. Address 1 is the grid page: 1 to 4 show the grid's
  * bytes 192·(page−1) to 192·page−1 at addresses 16 to 207 instead of the region buffer; 0 shows the regions again.
  * Pure, on the robot's clock (nanoseconds).
  *
  * @param regions
  *   the region buffer of the last finished capture (240 bytes)
  * @param grid
  *   the grid of the last finished capture (768 bytes)
  * @param lens
  *   what the camera sees now: the next capture's regions
  * @param busyUntil
  *   the end of the capture in progress; the camera is silent before it
  * @param page
  *   the grid page (address 1)
  * @param captures
  *   captures started since power-up
  */
final case class HaViMo2Device(
    regions: Vector[Byte],
    grid: Vector[Byte],
    lens: Vector[HaViMoRegion],
    busyUntil: Long,
    page: Int,
    captures: Long,
    captureNanos: Long
) {
  import HaViMo2Device._

  /** Whether the camera answers at `now` (no capture in progress). */
  def ready(now: Long): Boolean = now >= busyUntil

  /** The camera seeing `view` from now on (the next capture takes it). */
  def seeing(view: Vector[HaViMoRegion]): HaViMo2Device = copy(lens = view)

  /** Reads `length` bytes from `address`, or the error bits of a read past the camera's 256 addresses. */
  def read(address: Int, length: Int): Either[Int, Vector[Int]] =
    if (length < 1 || address + length > 256) Left(Dynamixel.RangeError)
    else Right((address until address + length).toVector.map(byteAt))

  private def byteAt(address: Int): Int =
    if (address == PageAddress) page
    else if (address < BufferAddress) 0
    else if (page == 0) regions(address - BufferAddress) & 0xff
    else {
      val offset = address - BufferAddress
      if (offset < PageBytes) grid((page - 1) * PageBytes + offset) & 0xff else 0
    }

  /** Writes `data` from `address` at `now`: address 0 starts a capture, address 1 sets the grid page (0-4). */
  def write(address: Int, data: Vector[Int], now: Long): (HaViMo2Device, Int) =
    if (data.isEmpty || address > PageAddress || address + data.length > PageAddress + 1) (this, Dynamixel.RangeError)
    else {
      val paged = if (address + data.length > PageAddress) data.last else page
      if (paged > GridPages) (this, Dynamixel.RangeError)
      else {
        val next = copy(page = paged)
        if (address == CaptureAddress) (next.capture(now), 0) else (next, 0)
      }
    }

  private def capture(now: Long): HaViMo2Device = {
    val records = HaViMo.encodeRegions(lens.take(HaViMo.MaxRegions).zipWithIndex.map { case (r, i) =>
        r.copy(index = i + 1)
      }).getOrElse(Array.emptyByteArray)
    val buffer = records.toVector ++ Vector.fill(RegionBufferBytes - records.length)(0.toByte)
    copy(regions = buffer, grid = naogateway.sim.Scene.grid(lens).toVector, busyUntil = now + captureNanos,
      captures = captures + 1)
  }
}

/** The camera's addresses and the emulation's figures. */
object HaViMo2Device {

  /** The HaViMo2's fixed id. */
  val Id: Int = 100

  /** A write here starts a capture. */
  val CaptureAddress: Int = 0

  /** The grid page register. */
  val PageAddress: Int = 1

  /** Where the region buffer (or a grid page) starts: slot i is at 16·i. */
  val BufferAddress: Int = 16

  /** The region buffer: 15 slots of 16 bytes. */
  val RegionBufferBytes: Int = HaViMo.MaxRegions * HaViMo.RegionRecordBytes

  /** Grid bytes per page, and pages: 4 × 192 = 768. */
  val PageBytes: Int = 192
  val GridPages: Int = 4

  /** How long a capture takes by default: within the camera's 19 frames a second. */
  val DefaultCaptureNanos: Long = 40000000L

  /** A camera that finished a capture of `view` at power-up. */
  def apply(view: Vector[HaViMoRegion], now: Long, captureNanos: Long = DefaultCaptureNanos): HaViMo2Device =
    HaViMo2Device(Vector.fill(RegionBufferBytes)(0.toByte), Vector.fill(HaViMo.GridCells)(0.toByte), view, now, 0, 0L,
      captureNanos).capture(now).copy(busyUntil = now, captures = 0L)
}
