package naogateway.sim.bus

import naogateway.proto.ServoState
import naogateway.wire.Dynamixel

/** One emulated AX-12A servo: its control table at the e-Manual's addresses, present position moving towards the goal
  * at the moving speed on the robot's clock (nanoseconds). Pure.
  *
  * @param table
  *   the 50 bytes of the control table; present position, speed, load, voltage and temperature are filled in as read
  * @param position
  *   the present position in control-table units, kept fractional so slow speeds move too
  * @param at
  *   the robot-clock time `position` holds for
  * @param registered
  *   a REG_WRITE waiting for ACTION: its address and bytes
  */
final case class Ax12(table: Vector[Int], position: Double, at: Long, registered: Option[(Int, Vector[Int])] = None) {
  import Ax12._

  /** The servo's id (address 3). */
  def id: Int = table(IdAddress)

  private def word(address: Int): Int = table(address) | (table(address + 1) << 8)

  /** The goal position (address 30). */
  def goal: Int = word(GoalPosition)

  /** The moving speed (address 32); 0 means the servo's maximum. */
  def movingSpeed: Int = word(MovingSpeed)

  /** Whether the motor holds or moves (address 24). */
  def torqueOn: Boolean = table(TorqueEnable) != 0

  /** Units per second the servo moves at: 0.111 rpm per speed unit, 300 degrees over 1023 units. */
  private def unitsPerSecond: Double = {
    val speed = if (movingSpeed == 0) MaxSpeedUnits else movingSpeed
    speed * 0.111 * 6.0 * 1023.0 / 300.0
  }

  /** The servo at `now`: the present position moved towards the goal while the torque is on. */
  def advance(now: Long): Ax12 =
    if (now <= at) this
    else if (!torqueOn || position == goal) copy(at = now)
    else {
      val step = unitsPerSecond * (now - at) / 1e9
      val next =
        if (math.abs(goal - position) <= step) goal.toDouble
        else position + math.signum(goal - position) * step
      copy(position = next, at = now)
    }

  /** Whether the servo is still on its way to the goal. */
  def moving: Boolean = torqueOn && math.round(position).toInt != goal

  /** The table as a read finds it now, with `volts` on the bus. */
  def readable(volts: Double): Vector[Int] = {
    val present = math.round(position).toInt.max(0).min(1023)
    val ccw = goal > present
    val speed = if (moving) math.min(1023, if (movingSpeed == 0) MaxSpeedUnits else movingSpeed) else 0
    val speedWord = speed | (if (moving && !ccw) DirectionBit else 0)
    val load = if (!torqueOn) 0 else if (moving) MovingLoad else HoldingLoad
    val loadWord = load | (if (moving && !ccw) DirectionBit else 0)
    val temperature = BaseTemperature + (if (torqueOn) 2 else 0) + (if (moving) 2 else 0)
    table
      .updated(PresentPosition, present & 0xff).updated(PresentPosition + 1, present >> 8)
      .updated(PresentSpeed, speedWord & 0xff).updated(PresentSpeed + 1, speedWord >> 8)
      .updated(PresentLoad, loadWord & 0xff).updated(PresentLoad + 1, loadWord >> 8)
      .updated(PresentVoltage, math.round(volts * 10).toInt.max(0).min(255))
      .updated(PresentTemperature, temperature)
      .updated(Registered, if (registered.isDefined) 1 else 0)
      .updated(Moving, if (moving) 1 else 0)
  }

  /** Reads `length` bytes from `address`: the bytes, or the error bits of a read outside the table. */
  def read(address: Int, length: Int, volts: Double): Either[Int, Vector[Int]] =
    if (length < 1 || address + length > TableBytes) Left(Dynamixel.RangeError)
    else Right(readable(volts).slice(address, address + length))

  /** Writes `data` from `address`: the servo after it, and the error bits (0 when all was written). A write that
    * touches a read-only byte or leaves the table writes nothing; goal position above 1023 is a range error. Writing
    * the goal position turns the torque on, as the AX-12A does.
    */
  def write(address: Int, data: Vector[Int]): (Ax12, Int) =
    if (data.isEmpty || address + data.length > TableBytes ||
      (address until address + data.length).exists(a => !Writable(a))) (this, Dynamixel.RangeError)
    else {
      val next = data.zipWithIndex.foldLeft(table) { case (t, (v, i)) => t.updated(address + i, v & 0xff) }
      val goalValue = next(GoalPosition) | (next(GoalPosition + 1) << 8)
      val touchesGoal = address <= GoalPosition + 1 && address + data.length > GoalPosition
      if (goalValue > 1023 || (next(MovingSpeed) | (next(MovingSpeed + 1) << 8)) > 1023) (this, Dynamixel.RangeError)
      else {
        val torque = if (touchesGoal) next.updated(TorqueEnable, 1) else next
        (copy(table = torque), 0)
      }
    }
}

/** The AX-12A's control table (ROBOTIS e-Manual addresses) and the emulation's figures. */
object Ax12 {
  val ModelNumber: Int = 0
  val FirmwareVersion: Int = 2
  val IdAddress: Int = 3
  val BaudRate: Int = 4
  val ReturnDelayTime: Int = 5
  val CwAngleLimit: Int = 6
  val CcwAngleLimit: Int = 8
  val TemperatureLimit: Int = 11
  val MinVoltageLimit: Int = 12
  val MaxVoltageLimit: Int = 13
  val MaxTorque: Int = 14
  val StatusReturnLevel: Int = 16
  val AlarmLed: Int = 17
  val Shutdown: Int = 18
  val TorqueEnable: Int = 24
  val Led: Int = 25
  val GoalPosition: Int = 30
  val MovingSpeed: Int = 32
  val TorqueLimit: Int = 34
  val PresentPosition: Int = 36
  val PresentSpeed: Int = 38
  val PresentLoad: Int = 40
  val PresentVoltage: Int = 42
  val PresentTemperature: Int = 43
  val Registered: Int = 44
  val Moving: Int = 46
  val Lock: Int = 47
  val Punch: Int = 48
  val TableBytes: Int = 50

  /** The AX-12A's model number (address 0). */
  val Model: Int = 12

  /** Bit 10 of present speed and present load: the direction (set: clockwise). */
  val DirectionBit: Int = 0x400

  /** Speed units at "moving speed 0": about 114 rpm without load. */
  val MaxSpeedUnits: Int = 1023

  private val MovingLoad = 200
  private val HoldingLoad = 30
  private val BaseTemperature = 34

  /** Bytes a write may change: the EEPROM settings from id on, and the RAM area but the present values. */
  val Writable: Set[Int] =
    ((IdAddress to 18) ++ (TorqueEnable to 35) ++ Seq(Lock, Punch, Punch + 1)).toSet - 10

  /** A servo of id `id` at its factory settings, at rest at `position` with the torque off, at robot time `now`. */
  def apply(id: Int, position: Int, now: Long): Ax12 = {
    val t = Array.fill(TableBytes)(0)
    def word(address: Int, value: Int): Unit = { t(address) = value & 0xff; t(address + 1) = (value >> 8) & 0xff }
    word(ModelNumber, Model)
    t(FirmwareVersion) = 24
    t(IdAddress) = id
    t(BaudRate) = 1
    t(ReturnDelayTime) = 250
    word(CwAngleLimit, 0)
    word(CcwAngleLimit, 1023)
    t(TemperatureLimit) = 70
    t(MinVoltageLimit) = 60
    t(MaxVoltageLimit) = 140
    word(MaxTorque, 1023)
    t(StatusReturnLevel) = 2
    t(AlarmLed) = 36
    t(Shutdown) = 36
    t(26) = 1
    t(27) = 1
    t(28) = 32
    t(29) = 32
    word(GoalPosition, position)
    word(TorqueLimit, 1023)
    word(Punch, 32)
    Ax12(t.toVector, position.toDouble, now)
  }

  /** What telemetry (docs/protocol.md 6.8) reports for a servo's table as read. */
  def state(table: Vector[Int]): ServoState = {
    val load = table(PresentLoad) | (table(PresentLoad + 1) << 8)
    val magnitude = load & 0x3ff
    ServoState(
      id = table(IdAddress),
      position = Some(table(PresentPosition) | (table(PresentPosition + 1) << 8)),
      load = Some(if ((load & DirectionBit) != 0) -magnitude else magnitude),
      voltage = Some(table(PresentVoltage)),
      temperature = Some(table(PresentTemperature))
    )
  }
}
