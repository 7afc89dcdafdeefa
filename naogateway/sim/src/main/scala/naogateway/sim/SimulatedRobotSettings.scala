package naogateway.sim

import java.net.{InetAddress, InetSocketAddress}

import scala.concurrent.duration._

import naogateway.sim.gs1500m.{Cm530Config, Cm530Stats, Gs1500mConfig, Gs1500mStats}
import naogateway.wire.{Posture, RpcCall}
import naogateway.wire.stream.StreamSettings

/** Settings of one simulated robot on a real UDP socket.
  *
  * @param firmware
  *   the simulated CM-530 firmware (robot id, team, role, timings, battery, scene, …)
  * @param gateway
  *   where keep-alives, debug output and secure-stream segments go (the gateway's robot port; 11011 in production)
  * @param bindAddress
  *   the robot's own IP address and the port it sends from (0: the operating system picks one, as the GS1500M's client
  *   connection gets a new one whenever it connects)
  * @param receivePort
  *   where the robot receives on its own IP address: requests, GameController packets and segments arrive at
  *   `bindAddress`'s IP on this port (3838, docs/protocol.md section 2; 0 lets the system pick one)
  * @param faithfulLink
  *   `true`: every datagram passes the GS1500M module and CM-530 models ([[FaithfulLink]]); `false`: datagrams go
  *   straight between socket and firmware, the cheap mode for big fleets
  * @param timeScale
  *   multiplies the modelled module and CM-530 durations (1.0 = the measured times)
  * @param resetBootDelay
  *   how long the robot is silent after a `system.reset` call while its module boots
  * @param module
  *   the GS1500M model; its own `timeScale` is replaced by `timeScale`
  * @param cpu
  *   the CM-530 main-loop model; its costs are replaced by `timeScale`, its keep-alive is switched off
  * @param seed
  *   the module's overflow coin and the main loop's random work
  * @param receiveBufferBytes
  *   the socket's receive buffer in the operating system
  * @param stream
  *   the robot's secure-stream endpoint, built afresh at every boot; `None`: segments are counted and ignored
  * @param keepAlivePhase
  *   the first keep-alive goes out this long after the start (at once after a power cycle), so a fleet's keep-alives
  *   need not all leave in the same instant
  */
final case class SimulatedRobotSettings(
    firmware: FirmwareSettings,
    gateway: InetSocketAddress,
    bindAddress: InetSocketAddress = SimulatedRobotSettings.AnyLoopbackPort,
    receivePort: Int = SimulatedRobot.ReceivePort,
    faithfulLink: Boolean = true,
    timeScale: Double = SimulatedRobotSettings.DefaultTimeScale,
    resetBootDelay: FiniteDuration = SimulatedRobot.ModuleBootDelay,
    module: Gs1500mConfig = Gs1500mConfig(),
    cpu: Cm530Config = Cm530Config(),
    seed: Long = 1L,
    receiveBufferBytes: Int = SimulatedRobotSettings.DefaultReceiveBufferBytes,
    stream: Option[RobotStream.Factory] = None,
    keepAlivePhase: FiniteDuration = Duration.Zero
) {
  require(timeScale > 0.0 && !timeScale.isInfinite, s"timeScale must be positive, is $timeScale")
  require(resetBootDelay >= Duration.Zero, "resetBootDelay must not be negative")
  require(receiveBufferBytes > 0, "receiveBufferBytes must be positive")
  require(keepAlivePhase >= Duration.Zero, "keepAlivePhase must not be negative")
  require(receivePort >= 0 && receivePort <= 65535, s"receivePort $receivePort is not a UDP port")

  /** These settings with the robot taking part in the secure stream: a fresh [[SecureStreamRobotStream]] with
    * `settings` at every boot (default: the thesis firmware's window 1, sequence numbers 0..20).
    */
  def withStream(settings: StreamSettings = StreamSettings.thesis): SimulatedRobotSettings =
    copy(stream = Some(SecureStreamRobotStream.factory(settings)))

  /** These settings with the servo telemetry (docs/protocol.md 6.8) read from `servos` (an emulated bus's `servos`)
    * once every `interval` instead of the built-in model.
    */
  def withServos(servos: () => Seq[naogateway.proto.ServoState],
      interval: FiniteDuration = firmware.servoTelemetryInterval): SimulatedRobotSettings =
    copy(firmware = firmware.copy(servoSource = Some(servos), servoTelemetryInterval = interval))
}

/** Defaults of [[SimulatedRobotSettings]]. */
object SimulatedRobotSettings {

  /** Port 0 on 127.0.0.1: the operating system picks a free port (to send from; it receives on 3838 there). */
  val AnyLoopbackPort: InetSocketAddress = new InetSocketAddress(InetAddress.getLoopbackAddress, 0)

  /** Modelled CM-530 and module times at 5 %: fast enough for tests, and the model still shapes every datagram. */
  val DefaultTimeScale: Double = 0.05

  /** Room for bursts in the operating system; the module model, not this buffer, is meant to be the bottleneck. */
  val DefaultReceiveBufferBytes: Int = 256 * 1024
}

/** What a simulated robot counted on its sockets, over its whole life (power cycles included).
  *
  * @param received
  *   datagrams that arrived at the receive socket (its IP at the receive port)
  * @param ignoredAtSendingSocket
  *   datagrams that arrived at the sending socket instead: the module's client connection passes nothing to the CM-530,
  *   so they are counted here and never acted on
  * @param busBridgeDropped
  *   bus bridge frames that came as plain datagrams instead of in the secure stream (docs/protocol.md 6.9)
  */
final case class RobotStats(
    received: Long = 0,
    sent: Long = 0,
    droppedWhileOff: Long = 0,
    streamSegments: Long = 0,
    oversizeDropped: Long = 0,
    powerCycles: Long = 0,
    ignoredAtSendingSocket: Long = 0,
    busBridgeDropped: Long = 0
)

/** One call as the simulated robot's firmware read it, at `atNanos` on the robot's clock (since its start). */
final case class ReceivedCall(atNanos: Long, call: RpcCall)

/** A snapshot of one simulated robot, for tests and tools.
  *
  * @param online
  *   `false` while the robot is powered off or its module boots (it neither sends nor answers)
  * @param onlineAgainIn
  *   while offline, the time left until the module answers again
  * @param uptimeMillis
  *   since the last power-up (or reset)
  * @param address
  *   where the robot receives (its IP at the receive port)
  * @param module
  *   stats of the GS1500M model since the last power-up (`None` without the faithful link)
  * @param cpu
  *   stats of the CM-530 main loop since the last power-up (`None` without the faithful link)
  * @param sendingFrom
  *   where the robot's datagrams come from now (its IP at the sending socket's port)
  * @param clock
  *   the robot's clock, which `uptimeMillis` and the keep-alives' timestamps read
  * @param bootedAtNanos
  *   when the firmware last booted, on this JVM's `System.nanoTime` (the gateway's clock when the gateway runs in the
  *   same JVM)
  */
final case class RobotView(
    robotId: Int,
    teamId: Int,
    role: String,
    address: InetSocketAddress,
    online: Boolean,
    onlineAgainIn: Option[FiniteDuration],
    bootId: Int,
    uptimeMillis: Long,
    posture: Posture,
    battery: Double,
    pose: Pose,
    head: (Double, Double),
    ball: (Double, Double),
    debugEnabled: Set[String],
    said: Vector[String],
    firmware: FirmwareStats,
    stats: RobotStats,
    module: Option[Gs1500mStats],
    cpu: Option[Cm530Stats],
    sendingFrom: InetSocketAddress,
    clock: RobotClock = RobotClock.Exact,
    bootedAtNanos: Long = 0L
) {

  /** When (on this JVM's `System.nanoTime`) the robot's clock read `robotMillis` in this session: the truth a clock
    * estimate is checked against.
    */
  def gatewayNanosOf(robotMillis: Long): Double = bootedAtNanos + clock.sinceBootNanosOf(robotMillis)
}
