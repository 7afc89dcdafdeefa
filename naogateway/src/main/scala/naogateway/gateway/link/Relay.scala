package naogateway.gateway.link

import java.net.InetSocketAddress

import scala.util.control.NonFatal

import org.slf4j.LoggerFactory

import naogateway.api.recording.Tapped
import naogateway.gateway.tap.Tap
import naogateway.proto.RecordedPort
import naogateway.transport.DatagramWriter

/** The FU-Remote relay: a reader of the gateway's tap that forwards every datagram the robot port received to `to`,
  * byte for byte, through `link` (whose sends the tap publishes as the relay port's), on a thread of its own: a relay
  * that falls behind drops and counts ([[naogateway.api.recording.TapReaderStats]]) and never slows the port.
  */
private[naogateway] final class Relay(link: DatagramWriter, to: InetSocketAddress, tap: Tap, capacity: Int,
    threadName: String) {
  private val log = LoggerFactory.getLogger(classOf[Relay])
  private val reader = tap.subscribe(Relay.ReaderName, capacity)
  // Written by the relay's thread only; read for the gateway's figures.
  @volatile private var sent = 0L
  @volatile private var running = true
  private val batch = new java.util.ArrayList[Tapped](Relay.Batch)
  private val thread = new Thread(() => loop(), threadName)
  thread.setDaemon(true)

  /** Datagrams forwarded so far. */
  def relayed: Long = sent

  /** Stops forwarding (waiting for the thread at most 5 s, never for the calling thread itself). */
  def close(): Unit = {
    running = false
    reader.close()
    if (thread ne Thread.currentThread()) thread.join(5000)
  }

  private def loop(): Unit =
    try {
      while (running) {
        batch.clear()
        if (reader.drainTo(batch, Relay.Batch) == 0) reader.await(Relay.IdleNanos)
        else {
          var i = 0
          var n = 0L
          while (i < batch.size) {
            batch.get(i) match {
              case d: Tapped.Datagram if d.port == RecordedPort.ROBOT_PORT && d.received =>
                if (link.send(d.bytes, to)) n += 1
              case _ => ()
            }
            i += 1
          }
          if (n > 0) sent += n
        }
      }
    } catch { case NonFatal(e) => log.error("The FU-Remote relay stopped", e) }
    finally reader.close()

  // Last in the constructor: the thread reads the fields above.
  thread.start()
}

/** The relay's pace. */
private[naogateway] object Relay {

  /** Datagrams the relay's queue holds while it is behind. */
  val Capacity: Int = 16384

  /** The relay's name among the tap's readers. */
  val ReaderName: String = "fu-remote-relay"

  /** Entries taken from the tap at a time. */
  private val Batch = 256

  /** The longest wait with nothing to forward: an offer wakes the relay at once; this only bounds a missed close. */
  private val IdleNanos = 1000000000L
}
