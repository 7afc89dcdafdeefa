package naogateway

/** What one keep-alive did: the robot's new snapshot, whether it completed a new session, and the restart rule now. */
final case class KeepAliveStep(snapshot: RobotSnapshot, restarted: Boolean, sessions: SessionRule)

/** The restart rule over a robot's snapshot: the gateway's logic beside the data apps see (`RobotSnapshot`, api). */
object KeepAliveStep {

  /** One keep-alive applied to the gateway's view of a robot: the snapshot it publishes
    * ([[RobotSnapshot.afterKeepAlive]]), and whether it completes a new session by the restart rule of docs/protocol.md
    * §6.2 ([[SessionRule]]: `keepAlives` keep-alives in a row of one new session). The rule's state is kept apart from
    * the snapshot, which shows only the latest keep-alive.
    */
  def keepAlive(
      previous: RobotSnapshot,
      sessions: SessionRule,
      status: naogateway.proto.Status,
      health: Option[naogateway.proto.RobotHealth],
      receivedAtNanos: Long,
      keepAlives: Int
  ): KeepAliveStep = {
    val current = RobotSnapshot.afterKeepAlive(previous, status, health, receivedAtNanos)
    val (next, restarted) =
      sessions.step(SessionMark(current.bootId, current.uptimeMillis, receivedAtNanos / 1000000L), keepAlives)
    KeepAliveStep(current, restarted, next)
  }
}
