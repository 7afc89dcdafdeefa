package naogateway.gateway.robot

import naogateway.api.RobotSnapshot

/** What one keep-alive did: the robot's new snapshot, whether it completed a new session, and the restart rule now. */
final case class KeepAliveStep(snapshot: RobotSnapshot, restarted: Boolean, sessions: SessionRule)

/** The restart rule over a robot's snapshot: the gateway's logic beside the data apps see (`RobotSnapshot`, api). */
object KeepAliveStep {

  /** One keep-alive (with the servo telemetry it carries, if any) applied to the gateway's view of a robot: the
    * snapshot it publishes ([[RobotSnapshot.afterKeepAlive]]), and whether it completes a new session by the restart
    * rule of docs/protocol.md §6.2 ([[SessionRule]]: `keepAlives` keep-alives in a row of one new session). The rule's
    * state is kept apart from the snapshot, which shows only the latest keep-alive.
    */
  def keepAlive(
      previous: RobotSnapshot,
      sessions: SessionRule,
      status: naogateway.proto.Status,
      health: Option[naogateway.proto.RobotHealth],
      receivedAtNanos: Long,
      keepAlives: Int,
      servos: Option[naogateway.proto.ServoTelemetry] = None
  ): KeepAliveStep = {
    val read = RobotSnapshot.afterKeepAlive(previous, status, health, receivedAtNanos, servos)
    val (next, restarted) =
      sessions.step(SessionMark(read.bootId, read.uptimeMillis, receivedAtNanos / 1000000L), keepAlives)
    // A new session's servos are unknown until its own telemetry arrives (§6.8): the old session's are dropped.
    val current = if (restarted && servos.isEmpty) read.copy(servos = None) else read
    KeepAliveStep(current, restarted, next)
  }
}
