package naogateway

import java.net.InetSocketAddress

import scala.concurrent.duration.FiniteDuration

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

/** What the gateway last heard from a robot's keep-alive. */
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
    receivedAtNanos: Long = 0L
) {

  /** What the robot reported about itself, as a keep-alive says it (the link fields are not part of it). */
  def report: RobotReport =
    RobotReport(teamId, role, agent, posture, batteryVoltage, uptimeMillis, bootId, position)
}

/** What one keep-alive did: the robot's new snapshot, whether it began a fresh session, and the bootId now remembered. */
final case class KeepAliveStep(snapshot: RobotSnapshot, restarted: Boolean, lastBootId: Option[Int])

/** How a keep-alive changes a robot's snapshot. */
object RobotSnapshot {

  /**
   * `previous` after one keep-alive (docs/protocol.md §6.2): the keep-alive describes the robot as it is now, so every
   * robot-reported field comes from it alone. A field it does not carry is unknown (`None`), never left over from an
   * earlier keep-alive: a robot that restarts with firmware sending `Status` only must not show the battery, role,
   * posture, position or `bootId` of its previous session. Link fields (address, online, quality) stay.
   */
  def afterKeepAlive(
      previous: RobotSnapshot,
      status: naogateway.proto.Status,
      health: Option[naogateway.proto.RobotHealth],
      receivedAtNanos: Long
  ): RobotSnapshot = {
    val r = RobotReport.read(status, health)
    previous.copy(
      teamId = r.teamId,
      role = r.role,
      agent = r.agent,
      posture = r.posture,
      batteryVoltage = r.batteryVoltage,
      uptimeMillis = r.uptimeMillis,
      bootId = r.bootId,
      position = r.position,
      receivedAtNanos = receivedAtNanos
    )
  }

  /**
   * One keep-alive applied to the gateway's view of a robot: the snapshot it publishes ([[afterKeepAlive]]), whether
   * the keep-alive starts a fresh session by the restart rule of docs/protocol.md §6.2, and the `bootId` the next
   * keep-alive is compared with. `lastBootId` is kept apart from the snapshot, which shows only the latest keep-alive.
   */
  def keepAlive(
      previous: RobotSnapshot,
      lastBootId: Option[Int],
      status: naogateway.proto.Status,
      health: Option[naogateway.proto.RobotHealth],
      receivedAtNanos: Long
  ): KeepAliveStep = {
    val current = afterKeepAlive(previous, status, health, receivedAtNanos)
    // A bootId differing from the last one seen (a keep-alive without one says nothing), or uptime going backwards by
    // more than a second (so reordered keep-alives are no restart).
    val restarted = (for (before <- lastBootId; now <- current.bootId) yield now != before).getOrElse(false) ||
      (for (before <- previous.uptimeMillis; after <- current.uptimeMillis) yield after + 1000 < before).getOrElse(false)
    // A restart announced without a bootId forgets the old session's, so it cannot make the next keep-alive a restart.
    KeepAliveStep(current, restarted, if (current.bootId.isDefined || restarted) current.bootId else lastBootId)
  }
}

/** Link figures of one robot. */
final case class LinkStats(
    robotId: Int,
    datagramsIn: Long,
    datagramsOut: Long,
    bytesIn: Long,
    bytesOut: Long,
    rttMillis: Option[Double],
    lossEstimate: Double,
    retransmissions: Long,
    rejected: Map[String, Long]
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

/** The GameController's latest packet. */
final case class GameStateUpdated(data: GameControlData) extends GatewayEvent

/** Why a call did not return a value. */
sealed trait CallError extends Product with Serializable {

  /** A sentence for logs and error replies. */
  def describe: String
}

/** The ways a call can fail. */
object CallError {

  /** The error an outbox outcome means for the call it carried, if any (`Accepted` is none). */
  def ofOutcome(robotId: Int, outcome: Outbox.Outcome): Option[CallError] = outcome match {
    case Outbox.Accepted(_)            => None
    case Outbox.RefusedByRule(_, rule) => Some(RuleGate(rule))
    case Outbox.Dropped(_, reason)     => Some(Overloaded(robotId, reason))
  }

  /** The robot answered with an error text. */
  final case class RobotError(robotId: Int, message: String) extends CallError {
    def describe: String = s"robot $robotId: $message"
  }

  /** The robot is offline; nothing was sent. */
  final case class RobotOffline(robotId: Int) extends CallError {
    def describe: String = s"robot $robotId is offline"
  }

  /** No robot with this id is known. */
  final case class UnknownRobot(robotId: Int) extends CallError {
    def describe: String = s"no robot $robotId is known"
  }

  /** No reply came in time (after the retries allowed). */
  final case class Timeout(robotId: Int, call: String, after: FiniteDuration) extends CallError {
    def describe: String = s"robot $robotId did not answer $call within ${after.toMillis} ms"
  }

  /** A competition rule forbids sending now. */
  final case class RuleGate(rule: String) extends CallError {
    def describe: String = rule
  }

  /** Too many calls wait already. */
  final case class Overloaded(robotId: Int, detail: String) extends CallError {
    def describe: String = s"robot $robotId is overloaded: $detail"
  }

  /** A newer command of the same kind replaced this one before it was sent (latest wins). */
  final case class Superseded(robotId: Int, call: String) extends CallError {
    def describe: String = s"$call to robot $robotId was replaced by a newer $call before it was sent"
  }

  /** The actor handling the call restarted before the reply came. */
  final case class Interrupted(robotId: Int, call: String) extends CallError {
    def describe: String = s"call $call to robot $robotId was interrupted by a restart of its handler"
  }
}

/** The one answer every call gets. */
final case class CallResult(robotId: Int, call: String, result: Either[CallError, Option[RpcValue]])
