package naogateway.sim.bus

import naogateway.wire.{Dynamixel, Posture}

/** The goal positions of the Bioloid-class humanoid's 18 AX-12A for each posture the simulated robot takes, and the one
  * sync write that sends them (docs/simulator.md 3.2). The figures are a plausible humanoid's, not a measured robot's:
  * they exist so that telemetry and a tool on the bus see the legs and arms move when the robot stands, sits, walks or
  * stops. Pure.
  */
object BodyPostures {

  /** A pose of the body: one of the tables below. Walking has two, one per step. */
  sealed abstract class Pose(val name: String) extends Product with Serializable

  /** The named poses. */
  object Pose {
    case object Sit extends Pose("sit")
    case object Stand extends Pose("stand")
    case object Crouch extends Pose("crouch")
    case object StepLeft extends Pose("step left")
    case object StepRight extends Pose("step right")
  }

  /** How long one step of the walk holds its pose, in nanoseconds (the gait alternates StepLeft and StepRight). */
  val StepNanos: Long = 400000000L

  /** How long a move to a new pose of the walk may take, in nanoseconds: the servos' speed is set from it. */
  val StepMoveNanos: Long = 300000000L

  // Ids 1-6 arms (shoulder pitch, shoulder roll, elbow; right and left alternating as on a Bioloid), 7-18 legs (hip
  // yaw, hip roll, hip pitch, knee, ankle pitch, ankle roll; right and left alternating).
  private val stand = Vector(512, 512, 412, 612, 512, 512, 512, 512, 512, 512, 512, 512, 482, 542, 572, 452, 512, 512)
  private val sit = Vector(512, 512, 360, 664, 620, 404, 512, 512, 512, 512, 312, 712, 812, 212, 352, 672, 512, 512)
  private val crouch = Vector(512, 512, 400, 624, 560, 464, 512, 512, 512, 512, 412, 612, 662, 362, 452, 572, 512, 512)
  // A step: one leg lifted (hip and knee bent further, ankle following), the opposite arm forward.
  private def step(left: Boolean): Vector[Int] = {
    val lifted = if (left) 1 else 0
    stand.zipWithIndex.map { case (p, i) =>
      val id = i + 1
      val side = id % 2 // ids alternate right (odd) and left (even)
      if (id >= 11 && id <= 16 && side == lifted) p + (if (side == 1) -60 else 60)
      else if (id <= 2 && side != lifted) p + (if (side == 1) 40 else -40)
      else p
    }
  }
  private val stepLeft = step(left = true)
  private val stepRight = step(left = false)

  /** The goal positions of `pose`, for ids 1-18 in order. */
  def goals(pose: Pose): Vector[Int] = pose match {
    case Pose.Sit       => sit
    case Pose.Stand     => stand
    case Pose.Crouch    => crouch
    case Pose.StepLeft  => stepLeft
    case Pose.StepRight => stepRight
  }

  /** The pose the body takes for a robot in `posture` (moving towards `target` when a posture change is under way) at
    * robot time `now` (a walk's step); None when the posture says nothing about the body (fallen, unknown).
    */
  def poseOf(posture: Posture, target: Option[Posture], now: Long): Option[Pose] =
    target.getOrElse(posture) match {
      case Posture.Sit     => Some(Pose.Sit)
      case Posture.Stand   => Some(Pose.Stand)
      case Posture.Crouch  => Some(Pose.Crouch)
      case Posture.Walking => Some(if ((now / StepNanos) % 2 == 0) Pose.StepLeft else Pose.StepRight)
      case _               => None
    }

  /** The sync write (address 30, goal position and moving speed per servo) that moves every servo of `bus` to `pose` in
    * about `withinNanos`: each servo's speed set so that all arrive together.
    */
  def syncWrite(bus: BioloidBus, pose: Pose, withinNanos: Long): Array[Byte] = {
    val seconds = math.max(0.05, withinNanos / 1e9)
    val target = goals(pose)
    val blocks = bus.tables.sortBy(_.id).filter(s => BioloidBus.ServoIds.contains(s.id)).flatMap { servo =>
      val goal = target(servo.id - 1)
      val distance = math.abs(goal - servo.position)
      // Units per second per speed unit: 0.111 rpm, 300 degrees over 1023 units (as Ax12 moves).
      val speed = math.max(1, math.min(1023, math.ceil(distance / seconds / (0.111 * 6.0 * 1023.0 / 300.0)).toInt))
      Seq(servo.id, goal & 0xff, goal >> 8, speed & 0xff, speed >> 8)
    }
    Dynamixel.packet(Dynamixel.BroadcastId, Dynamixel.SyncWrite, Seq(Ax12.GoalPosition, 4) ++ blocks)
  }

  /** The bus after the sync write that moves it to `pose` within `withinNanos`. */
  def move(bus: BioloidBus, pose: Pose, withinNanos: Long): BioloidBus =
    bus.transact(syncWrite(bus, pose, withinNanos))._1

  /** `bus` with every servo at rest in `pose`, its torque off: how a robot powers up where it was left. */
  def resting(bus: BioloidBus, pose: Pose): BioloidBus =
    bus.copy(tables = bus.tables.map(s =>
      if (BioloidBus.ServoIds.contains(s.id)) Ax12(s.id, goals(pose)(s.id - 1), bus.now) else s))
}
