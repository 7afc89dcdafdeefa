package naogateway.sim.bus

import com.google.protobuf.ByteString

import naogateway.proto.{BusBridge, BusResult}
import naogateway.wire.{Dynamixel, HaViMo}

/** What the simulated firmware does on its bus, as bus transactions: the camera's read cycle and the bus bridge's
  * requests (docs/protocol.md 6.9). Pure.
  */
object BusWork {

  /** One camera frame read over the bus: the region records in use (6.5 layout) and, when asked for, the 768 cells. */
  final case class CameraFrame(records: Array[Byte], grid: Option[Array[Byte]])

  private val GridReadBytes = 192

  // The cycle's instruction packets never change: built once.
  private val PingPacket = Dynamixel.packet(HaViMo2Device.Id, Dynamixel.Ping, Nil)
  private val RegionReads = Vector.tabulate(HaViMo.MaxRegions)(i =>
    Dynamixel.packet(HaViMo2Device.Id, Dynamixel.Read,
      Seq(HaViMo2Device.BufferAddress * (i + 1), HaViMo.RegionRecordBytes)))
  // READ_GRID in four reads of 192 cells (its address in 16-byte units).
  private val GridReads = Vector.tabulate(4)(part =>
    Dynamixel.packet(HaViMo2Device.Id, HaViMo2Device.ReadGrid, Seq(part * GridReadBytes / 16, GridReadBytes)))
  private val CapRegionPacket = Dynamixel.packet(HaViMo2Device.Id, HaViMo2Device.CapRegion, Nil)

  // The parameters of an error-free status of `length` parameters, else None.
  private def params(reply: Array[Byte], length: Int): Option[Vector[Int]] =
    Dynamixel.status(reply).filter(s => s.error == 0 && s.params.length == length).map(_.params)

  /** The camera's cycle, as the public CM-530 examples run it: a ping (no answer: the capture is still in progress, so
    * no frame), the 15 region slots read, the grid read (READ_GRID, 4 × 192 cells) when `withGrid`, and the next
    * capture started (CAP_REGION).
    */
  def cameraCycle(bus0: BioloidBus, withGrid: Boolean): (BioloidBus, Option[CameraFrame]) = {
    val (pinged, pong) = bus0.transact(PingPacket)
    if (Dynamixel.status(pong).isEmpty) (pinged, None)
    else {
      var bus = pinged
      val records = Array.newBuilder[Byte]
      RegionReads.foreach { packet =>
        val (next, reply) = bus.transact(packet)
        bus = next
        params(reply, HaViMo.RegionRecordBytes).filter(_.head != 0).foreach(_.foreach(b => records += b.toByte))
      }
      val grid = if (!withGrid) None
      else {
        val cells = Array.newBuilder[Byte]
        var whole = true
        GridReads.foreach { packet =>
          val (next, reply) = bus.transact(packet)
          bus = next
          params(reply, GridReadBytes).fold[Unit] { whole = false }(_.foreach(b => cells += b.toByte))
        }
        Some(cells.result()).filter(_ => whole)
      }
      bus = bus.transact(CapRegionPacket)._1
      (bus, Some(CameraFrame(records.result(), grid)))
    }
  }

  /** The robot's handling of one bridged request (docs/protocol.md 6.9): the bus after it and the reply to send. */
  def bridge(bus: BioloidBus, request: BusBridge, gateClosed: Boolean): (BioloidBus, BusBridge) = {
    def answer(result: BusResult, reply: Array[Byte] = Array.emptyByteArray) =
      BusBridge(request.sequence, reply = Some(ByteString.copyFrom(reply)).filter(!_.isEmpty), result = Some(result))
    request.request.map(_.toByteArray).filter(_.length <= Dynamixel.MaxRequestBytes).flatMap(b =>
      Dynamixel.instruction(b).map(b -> _)) match {
      case None                  => (bus, answer(BusResult.BUS_MALFORMED))
      case Some(_) if gateClosed => (bus, answer(BusResult.BUS_GATE_CLOSED))
      case Some((bytes, instruction)) =>
        val (next, reply) = bus.transact(bytes)
        val due = Dynamixel.statusBytesDue(instruction)
        val whole = if (due == 0) reply.isEmpty else reply.length == due && Dynamixel.status(reply).isDefined
        (next, answer(if (whole) BusResult.BUS_OK else BusResult.BUS_TIMEOUT, reply))
    }
  }
}
