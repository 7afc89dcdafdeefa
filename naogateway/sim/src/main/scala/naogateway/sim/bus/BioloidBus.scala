package naogateway.sim.bus

import naogateway.proto.ServoState
import naogateway.wire.{Dynamixel, HaViMoRegion}

/** The emulated Dynamixel protocol 1.0 bus of a Bioloid-class humanoid: 18 AX-12A servos (ids 1-18) and a HaViMo2 at id
  * 100 (docs/protocol.md 6.9). Pure and byte-level: [[transact]] takes one instruction packet and gives the status
  * bytes the bus returns (none for broadcast, sync write, a status-return level that answers nothing, an id nobody has,
  * a busy camera or a damaged packet). Time is the robot's clock in nanoseconds, moved on with [[advance]].
  *
  * @param now
  *   the bus's time
  * @param tables
  *   the servos, in id order at power-up
  * @param camera
  *   the HaViMo2
  * @param volts
  *   the battery's voltage, as every servo reads it
  */
final case class BioloidBus(now: Long, tables: Vector[Ax12], camera: HaViMo2Device, volts: Double) {
  import Dynamixel._

  /** The bus at `now` (never backwards): the servos moved on. */
  def advance(t: Long): BioloidBus =
    if (t <= now) this else copy(now = t, tables = tables.map(_.advance(t)))

  /** The bus with the battery at `v` volts. */
  def withVolts(v: Double): BioloidBus = copy(volts = v)

  /** The camera seeing `view` from now on. */
  def seeing(view: Vector[HaViMoRegion]): BioloidBus =
    if (view eq camera.lens) this else copy(camera = camera.seeing(view))

  /** Every servo as a read of its present values finds it now (docs/protocol.md 6.8), in id order. */
  def servos: Seq[ServoState] = tables.sortBy(_.id).map(s => Ax12.state(s.readable(volts)))

  /** One transaction at [[now]]: the bus after `packet` and the status bytes that came back (empty when none). */
  def transact(packet: Array[Byte]): (BioloidBus, Array[Byte]) =
    instruction(packet) match {
      case None                                  => (this, checksumError(packet))
      case Some(i) if i.instruction == SyncWrite => (syncWrite(i.params), Array.emptyByteArray)
      case Some(i) if i.id == BroadcastId        => (broadcast(i), Array.emptyByteArray)
      case Some(i) if i.id == HaViMo2Device.Id   => cameraTransaction(i)
      case Some(i) =>
        tables.indexWhere(_.id == i.id) match {
          case -1    => (this, Array.emptyByteArray)
          case index => servoTransaction(index, i)
        }
    }

  // A packet whole but for its checksum is answered with the checksum error bit by the device it names, as an AX-12A
  // does; anything else damaged is noise nobody answers.
  private def checksumError(packet: Array[Byte]): Array[Byte] =
    if (packet.length < MinPacketBytes || (packet(0) & 0xff) != 0xff || (packet(1) & 0xff) != 0xff ||
      packet.length != (packet(3) & 0xff) + 4) Array.emptyByteArray
    else {
      val id = packet(2) & 0xff
      if ((id == HaViMo2Device.Id && camera.ready(now)) || tables.exists(_.id == id))
        Status(id, ChecksumError, Vector.empty).bytes
      else Array.emptyByteArray
    }

  private def answers(servo: Ax12, instruction: Int): Boolean = servo.table(Ax12.StatusReturnLevel) match {
    case 0 => instruction == Ping
    case 1 => instruction == Ping || instruction == Read
    case _ => true
  }

  private def servoTransaction(index: Int, i: Instruction): (BioloidBus, Array[Byte]) = {
    val servo = tables(index)
    val (next, error, params) = servoStep(servo, i)
    val bus = copy(tables = tables.updated(index, next))
    if (!answers(servo, i.instruction)) (bus, Array.emptyByteArray)
    else (bus, Status(next.id, error, params).bytes)
  }

  /** What one servo does with an instruction: itself after it, the error bits and the status parameters. */
  private def servoStep(servo: Ax12, i: Instruction): (Ax12, Int, Vector[Int]) = i.instruction match {
    case Ping => (servo, 0, Vector.empty)
    case Read if i.params.length == 2 =>
      servo.read(i.params(0), i.params(1), volts).fold(e => (servo, e, Vector.empty), bytes => (servo, 0, bytes))
    case Write if i.params.length >= 2 =>
      val (next, error) = servo.write(i.params(0), i.params.drop(1))
      (next, error, Vector.empty)
    case RegWrite if i.params.length >= 2 =>
      (servo.copy(registered = Some(i.params(0) -> i.params.drop(1))), 0, Vector.empty)
    case Action => (act(servo), 0, Vector.empty)
    case Reset =>
      (Ax12(servo.id, math.round(servo.position).toInt, now).copy(position = servo.position), 0, Vector.empty)
    case _ => (servo, InstructionError, Vector.empty)
  }

  private def act(servo: Ax12): Ax12 =
    servo.registered.fold(servo) { case (address, data) => servo.write(address, data)._1.copy(registered = None) }

  // Broadcast: every servo acts, none answers (the camera takes no broadcast).
  private def broadcast(i: Instruction): BioloidBus =
    if (i.instruction == Ping || i.instruction == Read) this
    else copy(tables = tables.map(s => servoStep(s, i)._1))

  // Sync write: start address, data length, then id and data per servo.
  private def syncWrite(params: Vector[Int]): BioloidBus =
    if (params.length < 2 || params(1) < 1) this
    else {
      val address = params(0)
      val length = params(1)
      params.drop(2).grouped(length + 1).filter(_.length == length + 1).foldLeft(this) { (bus, block) =>
        bus.tables.indexWhere(_.id == block.head) match {
          case -1    => bus
          case index => bus.copy(tables = bus.tables.updated(index, bus.tables(index).write(address, block.tail)._1))
        }
      }
    }

  private def cameraTransaction(i: Instruction): (BioloidBus, Array[Byte]) =
    if (!camera.ready(now)) (this, Array.emptyByteArray)
    else {
      def status(error: Int, params: Vector[Int]) = Status(HaViMo2Device.Id, error, params).bytes
      i.instruction match {
        case Ping => (this, status(0, Vector.empty))
        case Read if i.params.length == 2 =>
          (this, camera.read(i.params(0), i.params(1)).fold(e => status(e, Vector.empty), b => status(0, b)))
        case HaViMo2Device.ReadGrid if i.params.length == 2 =>
          (this, camera.readGrid(i.params(0), i.params(1)).fold(e => status(e, Vector.empty), b => status(0, b)))
        // A capture answers nothing: the camera is busy from now on.
        case HaViMo2Device.CapRegion | HaViMo2Device.CapGrid =>
          (copy(camera = camera.capture(now)), Array.emptyByteArray)
        case Write if i.params.length >= 2 && i.params(0) == HaViMo2Device.CaptureAddress =>
          (copy(camera = camera.capture(now)), Array.emptyByteArray)
        case Write => (this, status(RangeError, Vector.empty))
        case _     => (this, status(InstructionError, Vector.empty))
      }
    }
}

/** Building the bus. */
object BioloidBus {

  /** The servos' ids. */
  val ServoIds: Range.Inclusive = 1 to 18

  /** A powered-up bus at robot time `now`: every servo at rest at its centre (512) with the torque off, the camera with
    * a finished capture of `view`, the battery at `volts`.
    */
  def apply(now: Long, view: Vector[HaViMoRegion] = Vector.empty, volts: Double = 12.0): BioloidBus =
    BioloidBus(now, ServoIds.toVector.map(id => Ax12(id, 512, now)), HaViMo2Device(view, now), volts)
}
