package naogateway.wire

import naogateway.proto.{Position, RobotHealth, Status}

/** What a robot says about itself in one keep-alive (docs/protocol.md §6.2): the fields of `Status` and `RobotHealth`
  * as values. The one mapping between those messages and the robot's reported state: the gateway reads keep-alives with
  * [[RobotReport.read]], and whoever sends one (the simulated firmware, the ZeroMQ endpoint) writes it with [[status]]
  * and [[health]].
  */
final case class RobotReport(
    teamId: Option[Int] = None,
    role: Option[String] = None,
    agent: Option[String] = None,
    posture: Option[Posture] = None,
    batteryVoltage: Option[Double] = None,
    uptimeMillis: Option[Long] = None,
    bootId: Option[Int] = None,
    position: Option[(Int, Int, Double)] = None,
    development: Boolean = false
) {

  /** The `Status` part: team, position (mm, mm, rad), agent, role, uptime and the posture as `currentState`. */
  def status: Status = Status(
    timestamp = uptimeMillis,
    teamID = teamId,
    timeOnline = uptimeMillis.map(ms => (ms / 1000L).toInt),
    robotPosition = position.map { case (x, y, r) => Position(Some(x), Some(y), Some(r.toFloat)) },
    activeAgent = agent,
    activeRole = role,
    currentState = posture.map(_.name)
  )

  /** The `RobotHealth` part: battery, posture, uptime (32 bits on the wire), `bootId`, and `development` when set. */
  def health: RobotHealth = RobotHealth(
    batteryVoltage = batteryVoltage.map(_.toFloat),
    posture = posture.map(_.name),
    uptimeMs = uptimeMillis.map(ms => (ms & 0xffffffffL).toInt),
    bootId = bootId,
    development = if (development) Some(true) else None
  )

  /** The keep-alive of robot `robotId`: a `Message` with `status` and `robotHealth`. */
  def contents(robotId: Int): MessageContents =
    MessageContents(robotId, status = Some(status), robotHealth = Some(health))
}

/** Reading a keep-alive. */
object RobotReport {

  /** What one keep-alive says: `RobotHealth` where it carries a field, else what `Status` has for it (posture from
    * `currentState`, uptime from `timestamp`). A field neither carries is `None`.
    */
  def read(status: Status, health: Option[RobotHealth]): RobotReport = RobotReport(
    teamId = status.teamID.map(_.toInt),
    role = status.activeRole,
    agent = status.activeAgent,
    posture = health.flatMap(_.posture).orElse(status.currentState).map(Posture.reported),
    batteryVoltage = health.flatMap(_.batteryVoltage).map(_.toDouble),
    uptimeMillis = health.flatMap(_.uptimeMs).map(_ & 0xffffffffL).orElse(status.timestamp),
    bootId = health.flatMap(_.bootId),
    position = status.robotPosition.map(p => (p.getX, p.getY, p.getRotation.toDouble)),
    development = health.exists(_.development.contains(true))
  )
}
