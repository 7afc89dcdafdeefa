package naogateway.sim.network

import java.net.InetSocketAddress

import naogateway.sim.SeededRandom

/** Handle of one proxy of a [[LossyNetwork]].
  *
  * @param id
  *   the proxy's creation index within its network (it also selects the proxy's random streams)
  * @param gateway
  *   where the proxy forwards the robot's datagrams
  * @param clientSide
  *   the address the robot must send to (and where the gateway's datagrams come from, seen by the robot)
  * @param upstream
  *   the address the gateway sees as the robot's source: the robot's IP as far as the gateway knows
  * @param receiveSide
  *   where the gateway must send to reach the robot: `upstream`'s IP at the robot receive port
  */
final case class Proxy(
    id: Int,
    gateway: InetSocketAddress,
    clientSide: InetSocketAddress,
    upstream: InetSocketAddress,
    receiveSide: InetSocketAddress
)

/** What one direction of one proxy did with its datagrams.
  *
  * `received == forwarded + droppedLoss + droppedPartition + undeliverable` always holds. `duplicated` counts the extra
  * copies, `reordered` the forwarded datagrams that were held back, and `sendFailures` the copies the operating system
  * refused (full socket buffer or an I/O error). `atSourcePort` (downlink only) counts datagrams the gateway sent to
  * the robot's source port instead of its receive port: like a real robot's module, the proxy never passes them on.
  */
final case class DirectionStats(
    received: Long = 0,
    forwarded: Long = 0,
    droppedLoss: Long = 0,
    droppedPartition: Long = 0,
    duplicated: Long = 0,
    reordered: Long = 0,
    undeliverable: Long = 0,
    sendFailures: Long = 0,
    atSourcePort: Long = 0
) {

  /** Datagrams dropped on purpose (loss and partition). */
  def dropped: Long = droppedLoss + droppedPartition
}

/** Stats of both directions of one proxy. */
final case class ProxyStats(uplink: DirectionStats, downlink: DirectionStats) {

  /** The stats of one direction. */
  def apply(direction: Direction): DirectionStats = direction match {
    case Direction.Uplink   => uplink
    case Direction.Downlink => downlink
  }
}

/** One direction of a proxy as its network thread keeps it: the impairment, its random stream and the counts. */
private[network] final class LinkState(var impairment: Impairment, var rng: SeededRandom) {
  var received = 0L
  var forwarded = 0L
  var droppedLoss = 0L
  var droppedPartition = 0L
  var duplicated = 0L
  var reordered = 0L
  var undeliverable = 0L
  var sendFailures = 0L
  var atSourcePort = 0L

  def stats: DirectionStats =
    DirectionStats(
      received,
      forwarded,
      droppedLoss,
      droppedPartition,
      duplicated,
      reordered,
      undeliverable,
      sendFailures,
      atSourcePort
    )
}
