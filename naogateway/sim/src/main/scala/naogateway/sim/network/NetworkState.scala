package naogateway.sim.network

import java.io.IOException
import java.net.{InetSocketAddress, StandardProtocolFamily, StandardSocketOptions}
import java.nio.channels.DatagramChannel

import java.util.concurrent.CompletableFuture

import scala.util.control.NonFatal

import org.slf4j.LoggerFactory

/** A request handed to the network thread, answered through its future. */
private[network] final class Task[A](body: () => A) {
  val result = new CompletableFuture[A]()

  def run(): Unit =
    try result.complete(body())
    catch { case NonFatal(e) => result.completeExceptionally(e) }

  def abandon(reason: Throwable): Unit = result.completeExceptionally(reason)
}

/** One proxy of a [[LossyNetwork]]: its three sockets, its two links and where it delivers; touched only by the
  * network's thread.
  */
private[network] final class ProxyState(
    val handle: Proxy,
    clientChannel: DatagramChannel,
    val upstreamChannel: DatagramChannel,
    receiveChannel: DatagramChannel,
    uplink: LinkState,
    downlink: LinkState,
    val fixedRobot: Option[InetSocketAddress],
    val receivePort: Int
) {
  var open = true
  var robot: Option[InetSocketAddress] = fixedRobot

  def link(direction: Direction): LinkState = direction match {
    case Direction.Uplink   => uplink
    case Direction.Downlink => downlink
  }

  def receivingChannel(direction: Direction): DatagramChannel = direction match {
    case Direction.Uplink   => clientChannel
    case Direction.Downlink => receiveChannel
  }

  def sendingChannel(direction: Direction): DatagramChannel = direction match {
    case Direction.Uplink   => upstreamChannel
    case Direction.Downlink => clientChannel
  }

  def stats: ProxyStats = ProxyStats(uplink.stats, downlink.stats)

  def close(): Unit = {
    open = false
    List(clientChannel, upstreamChannel, receiveChannel).foreach { channel =>
      try channel.close()
      catch { case e: IOException => ProxyState.log.warn("Proxy [{}] could not close a socket", Int.box(handle.id), e) }
    }
  }
}

/** What a selected socket is: one proxy's receiving side of one direction. */
private[network] final case class Endpoint(state: ProxyState, direction: Direction)

/** The upstream socket of a proxy, where datagrams sent to a robot's source port arrive and are dropped. */
private[network] final case class AtSourcePort(state: ProxyState)

/** A delayed copy of a datagram, due at `dueNanos`. */
private[network] final case class PendingCopy(
    dueNanos: Long,
    sequence: Long,
    state: ProxyState,
    direction: Direction,
    bytes: Array[Byte],
    to: InetSocketAddress
)

private[network] object PendingCopy {
  // PriorityQueue dequeues its largest element, hence the reversal. Deadlines from nanoTime are compared by their
  // difference, as its values may be negative; the sequence keeps copies due at the same instant in arrival order.
  val earliestFirst: Ordering[PendingCopy] = new Ordering[PendingCopy] {
    def compare(a: PendingCopy, b: PendingCopy): Int = {
      val byDue = java.lang.Long.signum(b.dueNanos - a.dueNanos)
      if (byDue != 0) byDue else java.lang.Long.compare(b.sequence, a.sequence)
    }
  }
}

private[network] object ProxyState {
  private val log = LoggerFactory.getLogger(classOf[LossyNetwork])
}

/** Opening the network's sockets. */
private[network] object Sockets {
  private val SocketBuffer: Integer = 1 << 20

  /** A non-blocking datagram socket bound to `address`, with the network's socket buffers; closed again if that fails.
    */
  def openChannel(address: InetSocketAddress): DatagramChannel = {
    val channel = DatagramChannel.open(StandardProtocolFamily.INET)
    try {
      channel.setOption[Integer](StandardSocketOptions.SO_RCVBUF, SocketBuffer)
      channel.setOption[Integer](StandardSocketOptions.SO_SNDBUF, SocketBuffer)
      channel.bind(address)
      channel.configureBlocking(false)
      channel
    } catch {
      case NonFatal(e) =>
        channel.close()
        throw e
    }
  }

  /** The address a bound socket has. */
  def localAddress(channel: DatagramChannel): InetSocketAddress =
    channel.getLocalAddress match {
      case address: InetSocketAddress => address
      case other                      => throw new IOException(s"unexpected local address $other")
    }
}
