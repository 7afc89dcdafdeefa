package naogateway.api

import java.net.InetSocketAddress

import naogateway.api.recording.{RecordingStats, TapReaderStats}

/** Where the game state comes from, for the status view and robotctl (the answer to `GatewayAccess.GetGameSource`).
  *
  * @param trusted
  *   the configured GameController addresses or subnets, in words ("any source" when none is)
  * @param lastFrom
  *   the sender of the last control packet that counted
  * @param untrusted
  *   control packets ignored because they came from elsewhere
  * @param budget
  *   the team's message budget in one line, when the gateway counts it (`MessageBudget.describe`)
  * @param warnings
  *   what needs the team's attention: a second GameController, the message budget
  * @param trueStateAgeMillis
  *   in the monitor role: how old the last true game state (`RGTD`) is; `None` before the first
  * @param forwarded
  *   in the monitor role: the robots' status messages the GameController forwarded, by team and player
  */
final case class GameSource(trusted: String, lastFrom: Option[InetSocketAddress], untrusted: Long,
    budget: Option[String] = None, warnings: Vector[String] = Vector.empty, trueStateAgeMillis: Option[Long] = None,
    forwarded: Vector[ForwardedStatus] = Vector.empty) {

  /** One line: "game state from 10.0.0.5:3838 (trusted: 10.0.0.0/24), 3 packets from elsewhere ignored". */
  def describe: String =
    s"game state from ${lastFrom.fold("nowhere yet")(a => s"${a.getAddress.getHostAddress}:${a.getPort}")} " +
      s"(trusted: $trusted)" +
      (if (untrusted > 0) s", $untrusted packet(s) from elsewhere ignored" else "")
}

/** Where the gateway listens (the answer to `GatewayAccess.GetAddresses`). */
final case class GatewayAddresses(robots: InetSocketAddress, gameController: Option[InetSocketAddress])

/** The link figures of every robot whose actor answered `GetLinkStats` in time, by robot id. */
final case class RobotLinks(links: Vector[LinkStats])

/** The gateway's own figures: datagrams seen, relayed, refused by kind (a closed set, `Rejection`) and by source
  * address (at most `RejectionLedger.SourceAddresses` of them, the rest under "other addresses"), and each reader of
  * its tap (the recorder, the live feed, the relay) with what it lost.
  */
final case class GatewayStats(datagramsIn: Long, relayed: Long, gameControllerPackets: Long,
    rejected: Map[String, Long], robots: Int,
    rejectedBySource: Map[String, Long] = Map.empty, recording: RecordingStats = RecordingStats.Off,
    replay: Option[ReplayProgress] = None, tap: Vector[TapReaderStats] = Vector.empty)
