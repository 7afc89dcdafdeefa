package naogateway.sim

import java.net.{InetAddress, InetSocketAddress}

import scala.concurrent.duration._

import naogateway.proto._
import naogateway.sim.bus.{BioloidBus, BodyPostures}
import naogateway.wire._
import naogateway.wire.gamecontroller.GameControlData

/** Settings of one simulated CM-530 firmware; every figure can be changed per robot. The battery drains (faster while
  * walking) and, while the robot sits below `sitChargeUpTo`, recharges at `sitChargePerSecond` up to it, as a team
  * swaps a sitting robot's low battery: a demo robot held safe for a low battery recovers (docs/simulator.md).
  * `fullBattery` is what a swapped battery reads (`robotctl battery <id> swap`). `servoTelemetryInterval`: one
  * keep-alive per interval carries servo telemetry (docs/protocol.md 6.8; zero turns it off); `servoSource` gives the
  * servos it reads (an emulated bus's `servos`), None the robot's emulated bus (`bus`). `gameControllerSource`: the
  * only address whose control packets count, as the C library's `gc_source` (on a shared WiFi anyone can send `RGme`);
  * None: any, as a `gc_source` of 0.0.0.0.
  */
final case class FirmwareSettings(
    robotId: Int,
    teamId: Int = 1,
    playerNumber: Int = 1,
    role: String = "striker",
    agent: String = "SimAgent",
    keepAliveInterval: FiniteDuration = 200.millis,
    walkLease: FiniteDuration = 500.millis,
    debugInterval: FiniteDuration = 100.millis,
    cameraInterval: FiniteDuration = 60.millis,
    standUpTime: FiniteDuration = 1500.millis,
    sitDownTime: FiniteDuration = 1000.millis,
    crouchTime: FiniteDuration = 600.millis,
    initialBattery: Double = 12.4,
    idleDrainPerSecond: Double = 0.0002,
    walkDrainPerSecond: Double = 0.004,
    postureChangeDrain: Double = 0.005,
    sitChargePerSecond: Double = 0.005,
    sitChargeUpTo: Double = 11.5,
    fullBattery: Double = 12.6,
    maxSpeed: Double = 0.3,
    maxTurn: Double = 1.0,
    startPose: Pose = Pose(-1.0, 0.0, 0.0),
    scene: Scene = Scene(0.5, 0.3),
    headerForm: HeaderForm = HeaderForm.Legacy,
    clock: RobotClock = RobotClock.Exact,
    signingKey: Option[SigningKey] = None,
    development: Boolean = false,
    servoTelemetryInterval: FiniteDuration = 1000.millis,
    servoSource: Option[() => Seq[ServoState]] = None,
    gameControllerSource: Option[InetAddress] = None
) {
  require(robotId >= 0, s"robotId must not be negative, got $robotId")

  /** The robot's own key, as `robotctl keys` derives it from the team key `signingKey` and a real robot is flashed
    * with: the simulator holds the team key only to derive this one.
    */
  lazy val robotKey: Option[RobotKey] = signingKey.map(_.robotKey(robotId))
  require(keepAliveInterval > Duration.Zero, "keepAliveInterval must be positive")
  require(walkLease > Duration.Zero, "walkLease must be positive")
  require(servoTelemetryInterval >= Duration.Zero, "servoTelemetryInterval must not be negative")
  require(cameraInterval.toNanos >= 1000000000L / HaViMo.MaxFramesPerSecond,
    s"the HaViMo2 delivers at most ${HaViMo.MaxFramesPerSecond} frames/s")
}

/** Where the firmware sends a datagram. */
sealed trait Destination extends Product with Serializable

/** The destinations a firmware knows. */
object Destination {

  /** The configured base station (the robot's keep-alive and debug target, port 11011). */
  case object Gateway extends Destination

  /** Back to the sender of the datagram being answered. */
  final case class ReplyTo(address: InetSocketAddress) extends Destination
}

/** A datagram the firmware wants on the air. */
final case class Outgoing(bytes: Array[Byte], to: Destination)

/** Stats of what a simulated firmware saw; tests read them. */
final case class FirmwareStats(
    datagramsIn: Long = 0,
    datagramsOut: Long = 0,
    rpcCalls: Long = 0,
    gameControllerPackets: Long = 0,
    gameControllerIgnored: Long = 0,
    rejected: Long = 0,
    refusedSignatures: Map[String, Long] = Map.empty,
    busBridgeRequests: Long = 0
)

/** A call whose reply waits until a motion ends. */
private[sim] final case class PendingReply(callId: Option[Long], to: Destination, form: HeaderForm)

/** A posture change under way. */
private[sim] final case class PostureChange(target: Posture, doneAt: Long, reply: PendingReply)

/** A walk command and the moment its lease runs out. */
private[sim] final case class Walk(vx: Double, vy: Double, omega: Double, leaseUntil: Long)

/** The whole state of a simulated CM-530 firmware; immutable, advanced by the functions of `RobotFirmware`. `bootId`
  * doubles as the boot counter of signed frames (kept in flash on a CM-530): it survives power cycles and resets.
  * `framesSigned` (the frame counter) and `gatewayWindow` (the last gateway timestamp accepted) start afresh at every
  * boot, as RAM does. `bus` is the robot's emulated Dynamixel bus (servos and HaViMo2), powered up at every boot;
  * `bodyPose` the pose whose goals its servos were last sent (FirmwareBody); `cameraView` what the camera's lens was
  * last given to see (FirmwareDebug).
  */
final case class FirmwareState(
    settings: FirmwareSettings,
    bootId: Int,
    bootedAt: Long,
    now: Long,
    battery: Double,
    posture: Posture,
    change: Option[PostureChange],
    walk: Option[Walk],
    pose: Pose,
    head: (Double, Double),
    arms: Vector[Double],
    debugEnabled: Set[String],
    nextKeepAliveAt: Long,
    nextDebugAt: Long,
    nextCameraAt: Long,
    frame: Int,
    said: Vector[String],
    game: Option[GameControlData],
    stats: FirmwareStats,
    framesSigned: Long = 0L,
    gatewayWindow: ReplayWindow = ReplayWindow.empty,
    nextServoTelemetryAt: Long = Long.MinValue,
    bus: BioloidBus = BioloidBus(0L),
    bodyPose: Option[BodyPostures.Pose] = None,
    cameraView: Option[CameraView] = None
) {

  /** The robot's clock: milliseconds since the firmware booted, as its [[RobotClock]] reads them. */
  def uptimeMillis: Long = settings.clock.millisAt(now - bootedAt)

  /** The next moment `RobotFirmware.advance` has something to do. */
  def nextWakeUp: Long = {
    val lease = walk.map(_.leaseUntil).getOrElse(Long.MaxValue)
    val motion = change.map(_.doneAt).getOrElse(Long.MaxValue)
    // Each debug clock counts only while one of its options is on: `advance` moves a clock on only then, so a clock
    // whose options are all off stays in the past and would otherwise call for a wake-up at once, again and again.
    val debug = if (debugEnabled.exists(o => !RobotFirmware.isCameraOption(o))) nextDebugAt else Long.MaxValue
    val camera = if (debugEnabled.exists(RobotFirmware.isCameraOption)) nextCameraAt else Long.MaxValue
    math.min(math.min(nextKeepAliveAt, lease), math.min(motion, math.min(debug, camera)))
  }

  /** The options the firmware offers, with their current switch. */
  def debugOptions: Vector[DebuggingOption] =
    RobotFirmware.OptionCatalogue.map { case (name, kind, text) =>
      DebuggingOption(name, Some(kind), Some(debugEnabled(name)), Some(text))
    }
}
