package naogateway.gateway.gamecontroller

import java.net.InetSocketAddress

import scala.concurrent.duration._

import naogateway.api.ForwardedStatus
import naogateway.gateway.StaticRobot

/** The monitor role at a version-19 GameController (`naogateway.game-controller.monitor`, docs/protocol.md 10.9):
  * opt-in, for a field whose rules allow it. The gateway asks for the true game state with `RGTr` and keeps asking
  * every `requestInterval`; the GameController then sends it `RGTD` on the GameController port and forwards every
  * robot's status message to `statusPort`.
  *
  * @param gameController
  *   the GameController's address and request port (3636)
  * @param statusPort
  *   where the forwarded status messages arrive (3940)
  * @param requestInterval
  *   how often the request is sent again (a GameController restarts a monitor's senders on each)
  * @param trueStateFresh
  *   how long after the last `RGTD` the broadcast `RGme` is not used for the gate and the view
  */
final case class MonitorSettings(
    gameController: InetSocketAddress,
    statusPort: Int = 3940,
    requestInterval: FiniteDuration = 2.seconds,
    trueStateFresh: FiniteDuration = 2.seconds
) {
  require(statusPort >= 0 && statusPort <= 65535, s"game-controller.monitor.status-port $statusPort is not a UDP port")
  require(requestInterval >= 100.millis, "game-controller.monitor.request-interval must be at least 100 ms")
}

/** The robots' status messages the GameController forwarded, by team and player, bounded. */
private[naogateway] final case class ForwardedStatuses(byPlayer: Map[(Int, Int), ForwardedStatus] = Map.empty) {

  /** After one forwarded status message; beyond [[ForwardedStatuses.MaxPlayers]] players the oldest makes room. */
  def add(f: ForwardedStatus): ForwardedStatuses = {
    val updated = byPlayer.updated(f.status.team -> f.status.player, f)
    ForwardedStatuses(
      if (updated.size <= ForwardedStatuses.MaxPlayers) updated else updated - updated.minBy(_._2.atNanos)._1)
  }

  /** The statuses by team and player number. */
  def sorted: Vector[ForwardedStatus] = byPlayer.toVector.sortBy(_._1).map(_._2)
}

/** Bounds of [[ForwardedStatuses]]. */
private[naogateway] object ForwardedStatuses {

  /** Players remembered: two teams of 20 slots. */
  val MaxPlayers: Int = 40
}

/** Checks of a monitor configuration. */
private[naogateway] object MonitorRole {

  /** Why `robots` would make this host send robot status messages itself, which the GameController answers by refusing
    * it as a monitor for good: a robot on this host (a loopback address, or the address the gateway listens on).
    */
  def conflicts(robots: Seq[StaticRobot], bindAddress: String): Vector[String] =
    robots.toVector.collect {
      case r if r.address.getAddress.isLoopbackAddress || r.address.getAddress.getHostAddress == bindAddress =>
        s"robot ${r.robotId} at ${r.address.getAddress.getHostAddress} runs on this host: its status messages to the " +
          "GameController would make it refuse this host as a monitor (game-controller.monitor needs every robot " +
          "elsewhere)"
    }
}
