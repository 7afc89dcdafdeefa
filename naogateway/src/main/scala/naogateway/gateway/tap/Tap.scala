package naogateway.gateway.tap

import java.net.InetSocketAddress
import java.util.concurrent.ArrayBlockingQueue
import java.util.concurrent.atomic.AtomicLong
import java.util.concurrent.locks.LockSupport

import org.slf4j.LoggerFactory

import naogateway.api.recording.{Decision, GatewayTap, TapReaderStats, TapSubscription, Tapped}
import naogateway.proto.RecordedPort
import naogateway.transport.RateLimitedLog

/** The gateway's one publisher of what crosses its ports: the port's reader, the outbox and the gateway publish here
  * from their own threads, and every reader (the recorder, the live feed, the FU-Remote relay) has a bounded queue of
  * its own. With no reader an entry is not even built: one volatile read on the hot path. A reader that falls behind
  * loses entries (counted for it alone); the publisher never waits.
  */
private[naogateway] final class Tap extends GatewayTap {
  // Replaced whole (copy on write) when a reader comes or goes: the publishers read it without a lock.
  @volatile private var current: Array[Tap.Reader] = Array.empty

  /** Whether any reader listens: publishers that build something only for the tap ask first. */
  def listening: Boolean = current.length != 0

  /** A datagram that passed `port`, `received` or sent, byte for byte; `robotId` the robot at the far end (-1: none).
    * `bytes` is shared with the readers: the caller must not change it afterwards.
    */
  def datagram(port: RecordedPort, received: Boolean, source: InetSocketAddress, destination: InetSocketAddress,
      bytes: Array[Byte], robotId: Int): Unit = {
    val readers = current
    if (readers.length != 0)
      publish(readers, Tapped.Datagram(System.nanoTime(), port, received, source, destination, bytes, robotId))
  }

  /** A decision of the gateway. */
  def decision(decision: Decision): Unit = {
    val readers = current
    if (readers.length != 0) publish(readers, Tapped.Decided(System.nanoTime(), decision))
  }

  private def publish(readers: Array[Tap.Reader], entry: Tapped): Unit = {
    var i = 0
    while (i < readers.length) { readers(i).offer(entry); i += 1 }
  }

  def subscribe(reader: String, capacity: Int): Tap.Reader = synchronized {
    val r = new Tap.Reader(reader, capacity, this)
    current = current :+ r
    r
  }

  private def remove(reader: Tap.Reader): Unit = synchronized { current = current.filterNot(_ eq reader) }

  def readers: Vector[TapReaderStats] = current.toVector.map(_.stats)
}

/** The tap's readers. */
private[naogateway] object Tap {

  private val log = LoggerFactory.getLogger(classOf[Tap])

  /** One reader's queue. Many threads offer; one thread (the reader's) drains and waits. */
  final class Reader private[Tap] (name: String, capacity: Int, tap: Tap) extends TapSubscription {
    private val queue = new ArrayBlockingQueue[Tapped](capacity)
    private val delivered = new AtomicLong
    private val dropped = new AtomicLong
    // The reader's thread while it waits in [[await]]: an offer then wakes it; otherwise an offer costs no wake-up.
    @volatile private var waiter: Thread = null
    @volatile private var open = true

    private[tap] def offer(entry: Tapped): Unit =
      if (queue.offer(entry)) {
        val w = waiter
        if (w ne null) LockSupport.unpark(w)
      } else {
        val n = dropped.incrementAndGet()
        if (RateLimitedLog.due(n))
          log.warn("The tap's reader {} dropped {} entries so far: it is behind (queue of {})", name,
            Long.box(n), Int.box(capacity))
      }

    def drainTo(into: java.util.Collection[_ >: Tapped], max: Int): Int = {
      val n = queue.drainTo(into, max)
      if (n > 0) delivered.addAndGet(n.toLong)
      n
    }

    /** Entries waiting. */
    def pending: Int = queue.size

    /** Whether the reader still listens. */
    def isOpen: Boolean = open

    /** Parks the calling thread (the reader's) until an entry is offered, [[close]] is called or `nanos` pass; at once
      * when entries wait.
      */
    def await(nanos: Long): Unit = {
      waiter = Thread.currentThread()
      // After the waiter is set: an offer before this check is seen here, one after it unparks.
      if (queue.isEmpty && open) LockSupport.parkNanos(nanos)
      waiter = null
    }

    def stats: TapReaderStats = TapReaderStats(name, delivered.get, dropped.get)

    /** Leaves the tap; what waits can still be drained. */
    def close(): Unit = {
      open = false
      tap.remove(this)
      val w = waiter
      if (w ne null) LockSupport.unpark(w)
    }
  }
}
