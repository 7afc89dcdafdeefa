package naogateway.sim.network

import java.io.IOException
import java.net.{DatagramPacket, DatagramSocket, InetAddress, InetSocketAddress}
import java.util.concurrent.{LinkedBlockingQueue, TimeUnit}

import scala.concurrent.duration._

/** A datagram a test peer received, with its source. */
final case class Received(bytes: Vector[Byte], from: InetSocketAddress)

/** A plain UDP endpoint standing in for the gateway or a robot (bound to `at`, 127.0.0.1 and a free port by default); a
  * reader thread drains its socket. It sends and receives on one socket.
  */
final class UdpPeer(label: String, at: InetSocketAddress = new InetSocketAddress(InetAddress.getLoopbackAddress, 0))
    extends AutoCloseable {
  private val socket = new DatagramSocket(at)
  socket.setReceiveBufferSize(1 << 20)
  private val inbox = new LinkedBlockingQueue[Received]()

  /** Where this peer receives. */
  val address: InetSocketAddress = socket.getLocalSocketAddress.asInstanceOf[InetSocketAddress]

  // Draining continuously keeps the kernel buffer from overflowing while a test sends bursts.
  private val reader = new Thread(() => readLoop(), s"udp-peer-$label")
  reader.setDaemon(true)
  reader.start()

  private def readLoop(): Unit = {
    val buffer = new Array[Byte](65536)
    while (!socket.isClosed) {
      val packet = new DatagramPacket(buffer, buffer.length)
      try {
        socket.receive(packet)
        inbox.add(
          Received(
            buffer.slice(packet.getOffset, packet.getOffset + packet.getLength).toVector,
            packet.getSocketAddress.asInstanceOf[InetSocketAddress]
          )
        )
      } catch { case _: IOException => () }
    }
  }

  /** Sends one datagram. */
  def send(bytes: Array[Byte], to: InetSocketAddress): Unit = socket.send(new DatagramPacket(bytes, bytes.length, to))

  /** The next datagram, if one arrives within `within`. */
  def receive(within: FiniteDuration = 5.seconds): Option[Received] =
    Option(inbox.poll(within.toMillis, TimeUnit.MILLISECONDS))

  /** Up to `n` datagrams, collected until `n` arrived or `within` passed. */
  def receiveUpTo(n: Int, within: FiniteDuration): Vector[Received] = {
    val deadline = within.fromNow
    val collected = Vector.newBuilder[Received]
    var count = 0
    while (count < n && deadline.hasTimeLeft()) {
      Option(inbox.poll(math.max(1L, deadline.timeLeft.toMillis), TimeUnit.MILLISECONDS)).foreach { r =>
        collected += r
        count += 1
      }
    }
    collected.result()
  }

  /** Everything that arrives during `window`. */
  def collectFor(window: FiniteDuration): Vector[Received] = receiveUpTo(Int.MaxValue, window)

  override def close(): Unit = {
    socket.close()
    reader.join(5000)
  }
}
