package naogateway.api

import naogateway.wire.ActuatorGroup

import java.net.InetSocketAddress

import naogateway.wire.{Posture, RobotReport, RpcValue}
import naogateway.wire.gamecontroller.GameControlData

/** How well a robot's link works, with hysteresis so a lossy link does not flap. */
sealed abstract class LinkQuality(val name: String) extends Product with Serializable

/** The three link qualities. */
object LinkQuality {
  case object Good extends LinkQuality("good")
  case object Degraded extends LinkQuality("degraded")
  case object Offline extends LinkQuality("offline")
}

/** Whether a robot's frames come signed as the gateway requires (docs/protocol.md 6.7). */
sealed abstract class SigningState(val name: String) extends Product with Serializable

/** The signing states of a robot. */
object SigningState {

  /** The gateway does not require this robot to sign (`signing = off`, or no team key). */
  case object Off extends SigningState("off")

  /** The robot must sign; nothing of it has arrived yet. */
  case object Awaited extends SigningState("awaited")

  /** The robot must sign, and its latest frame verified. */
  case object Signed extends SigningState("signed")

  /** The robot must sign, and its latest frame came unsigned or badly signed (refused): a robot without the right key
    * or a development build, not an offline one.
    */
  case object Unsigned extends SigningState("unsigned")

  /** Every state. */
  val all: Vector[SigningState] = Vector(Off, Awaited, Signed, Unsigned)
}

/** What the gateway last heard from a robot's keep-alive. `receivedAtNanos` and `stampedAtNanos` are on the gateway's
  * clock (its JVM's `System.nanoTime`); `stampedAtNanos` is when the robot's clock read this keep-alive's timestamp, by
  * the robot's clock estimate `clock` (None until there is one, or when the keep-alive carries no robot time). `servos`
  * is the latest servo telemetry of this session (docs/protocol.md 6.8), kept over keep-alives without one, gone when
  * the robot goes offline or restarts.
  */
final case class RobotSnapshot(
    robotId: Int,
    address: InetSocketAddress,
    teamId: Option[Int] = None,
    role: Option[String] = None,
    agent: Option[String] = None,
    posture: Option[Posture] = None,
    batteryVoltage: Option[Double] = None,
    uptimeMillis: Option[Long] = None,
    bootId: Option[Int] = None,
    position: Option[(Int, Int, Double)] = None,
    online: Boolean = false,
    quality: LinkQuality = LinkQuality.Offline,
    receivedAtNanos: Long = 0L,
    clock: Option[ClockEstimate] = None,
    stampedAtNanos: Option[Long] = None,
    development: Boolean = false,
    signing: SigningState = SigningState.Off,
    servos: Option[ServoReadings] = None
) {

  /** What the robot reported about itself, as a keep-alive says it (the link fields are not part of it). */
  def report: RobotReport =
    RobotReport(teamId, role, agent, posture, batteryVoltage, uptimeMillis, bootId, position, development)
}

/** How a keep-alive changes a robot's snapshot (the restart rule over it is the gateway's [[KeepAliveStep]]). */
object RobotSnapshot {

  /** `previous` after one keep-alive (docs/protocol.md §6.2): the keep-alive describes the robot as it is now, so every
    * robot-reported field comes from it alone. A field it does not carry is unknown (`None`), never left over from an
    * earlier keep-alive: a robot that restarts with firmware sending `Status` only must not show the battery, role,
    * posture, position or `bootId` of its previous session. Link fields (address, online, quality, signing) stay. Servo
    * telemetry is the one exception (§6.8): a keep-alive without it leaves the last one, unless the `bootId` changed.
    */
  def afterKeepAlive(
      previous: RobotSnapshot,
      status: naogateway.proto.Status,
      health: Option[naogateway.proto.RobotHealth],
      receivedAtNanos: Long,
      servos: Option[naogateway.proto.ServoTelemetry] = None
  ): RobotSnapshot = {
    val r = RobotReport.read(status, health)
    val telemetry = servos.map(ServoReadings.read(_, receivedAtNanos)) match {
      case None if r.bootId == previous.bootId => previous.servos
      case other                               => other
    }
    previous.copy(
      teamId = r.teamId,
      role = r.role,
      agent = r.agent,
      posture = r.posture,
      batteryVoltage = r.batteryVoltage,
      uptimeMillis = r.uptimeMillis,
      bootId = r.bootId,
      position = r.position,
      development = r.development,
      receivedAtNanos = receivedAtNanos,
      servos = telemetry
    )
  }
}

/** Link figures of one robot; `clock` is the estimate of the robot's clock against the gateway's (ClockSync). */
final case class LinkStats(
    robotId: Int,
    datagramsIn: Long,
    datagramsOut: Long,
    bytesIn: Long,
    bytesOut: Long,
    rttMillis: Option[Double],
    lossEstimate: Double,
    retransmissions: Long,
    rejected: Map[String, Long],
    clock: Option[ClockEstimate] = None
)

/** Something that happened to a robot or the game, for subscribers. */
sealed trait GatewayEvent extends Product with Serializable

/** Events about one robot. */
sealed trait RobotEvent extends GatewayEvent {

  /** The robot concerned. */
  def robotId: Int
}

/** The robot is reachable (first keep-alive, or back after being offline). */
final case class RobotOnline(robotId: Int, address: InetSocketAddress) extends RobotEvent

/** The robot missed its chances: unreachable until it speaks again or someone asks. */
final case class RobotOffline(robotId: Int, reason: String) extends RobotEvent

/** The link quality changed. */
final case class LinkQualityChanged(robotId: Int, quality: LinkQuality) extends RobotEvent

/** A keep-alive arrived. */
final case class RobotStatusUpdated(snapshot: RobotSnapshot) extends RobotEvent {
  def robotId: Int = snapshot.robotId
}

/** The robot came back with a fresh session; the gateway has re-synced it. */
final case class RobotRestarted(robotId: Int, bootId: Option[Int], resynced: Vector[String]) extends RobotEvent

/** A robot discovered from its keep-alives was forgotten (never online, or offline too long): its robot actor stopped,
  * its IP address and id are free. Its next keep-alive discovers it again. Configured robots are never forgotten.
  */
final case class RobotForgotten(robotId: Int, reason: String) extends RobotEvent

/** The GameController's latest packet. */
final case class GameStateUpdated(data: GameControlData) extends GatewayEvent

/** Why a call or an operation failed: the one error type of every caller, from a robot's response actor up to an app
  * using `RobotInterface` (an exception, so a failed `Future` carries it as it is).
  */
sealed abstract class RobotFailure(message: String) extends Exception(message) with Product with Serializable {

  /** A sentence for logs and error replies. */
  def describe: String = message
}

/** The ways a call or an operation can fail. */
object RobotFailure {

  /** The robot is offline; nothing was sent. */
  final case class RobotOffline(robotId: Int) extends RobotFailure(s"robot $robotId is offline")

  /** No robot with this id is known. */
  final case class UnknownRobot(robotId: Int) extends RobotFailure(s"no robot $robotId is known")

  /** The app does not hold the lease the operation needs. */
  final case class LeaseNotHeld(robotId: Int, group: ActuatorGroup, holder: Option[String])
      extends RobotFailure(
        s"lease '${group.name}' of robot $robotId is not held by this app" + holder.fold("")(h => s" (held by $h)"))

  /** A competition rule forbids sending now. */
  final case class RuleGate(rule: String) extends RobotFailure(rule)

  /** No answer in time (after the retries allowed). */
  final case class Timeout(robotId: Int, operation: String, millis: Long)
      extends RobotFailure(s"robot $robotId did not answer $operation within $millis ms")

  /** The robot answered with an error text. */
  final case class RobotError(robotId: Int, error: String) extends RobotFailure(s"robot $robotId: $error")

  /** The middleware holds the robot in a safe state (low battery, lost link) and refuses motion. */
  final case class SafetyHold(robotId: Int, reason: String)
      extends RobotFailure(s"robot $robotId is held safe: $reason")

  /** Too much is waiting for this robot. */
  final case class Overloaded(robotId: Int, detail: String)
      extends RobotFailure(s"robot $robotId is overloaded: $detail")

  /** A newer command of the same slot replaced this one (latest wins). */
  final case class Superseded(robotId: Int, call: String)
      extends RobotFailure(s"$call to robot $robotId was replaced by a newer one")

  /** The actor handling the call restarted before the reply came. */
  final case class Interrupted(robotId: Int, call: String)
      extends RobotFailure(s"call $call to robot $robotId was interrupted by a restart of its handler")
}

/** The one answer every call gets. */
final case class CallResult(robotId: Int, call: String, result: Either[RobotFailure, Option[RpcValue]])
