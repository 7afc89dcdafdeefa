package naogateway.gateway.tap

import java.net.InetSocketAddress
import java.util.concurrent.atomic.{AtomicLong, AtomicLongArray, AtomicReference, AtomicReferenceArray}
import java.util.concurrent.locks.LockSupport

import org.slf4j.LoggerFactory

import naogateway.api.recording.{Decision, GatewayTap, TapReaderStats, TapSubscription, Tapped}
import naogateway.proto.RecordedPort
import naogateway.wire.MessageContents
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

  /** A datagram that passed `port`, `received` or sent, byte for byte; `robotId` the robot at the far end (-1: none);
    * `decoded` the frame as the gateway decoded it, if it did. `bytes` is shared with the readers: the caller must not
    * change it afterwards.
    */
  def datagram(port: RecordedPort, received: Boolean, source: InetSocketAddress, destination: InetSocketAddress,
      bytes: Array[Byte], robotId: Int, decoded: Option[MessageContents] = None): Unit = {
    val readers = current
    if (readers.length != 0)
      publish(readers,
        Tapped.Datagram(System.nanoTime(), port, received, source, destination, bytes, robotId, decoded))
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
    private val queue = new RingQueue[Tapped](capacity)
    private val delivered = new AtomicLong
    private val dropped = new AtomicLong
    // The reader's thread while it waits in [[await]]: the first offer then takes it and wakes it (the offers after it
    // find none); while the reader is not waiting an offer costs one volatile read and no wake-up.
    private val waiter = new AtomicReference[Thread]
    // While the reader waits: how many waiting entries wake it (1 on an empty queue; more while it gathers a batch, so
    // a trickle wakes it once per pause, not once per entry, and a burst still wakes it long before the queue is full).
    @volatile private var wakeAt = 1
    @volatile private var open = true

    private[tap] def offer(entry: Tapped): Unit =
      if (queue.offer(entry)) {
        val w = waiter.get
        if ((w ne null) && queue.size >= wakeAt && waiter.compareAndSet(w, null)) LockSupport.unpark(w)
      } else {
        val n = dropped.incrementAndGet()
        if (RateLimitedLog.due(n))
          log.warn("The tap's reader {} dropped {} entries so far: it is behind (queue of {})", name,
            Long.box(n), Int.box(capacity))
      }

    def drainTo(into: java.util.Collection[_ >: Tapped], max: Int): Int = {
      var n = 0
      var next = if (max > 0) queue.poll() else null
      while (next ne null) {
        into.add(next)
        n += 1
        next = if (n < max) queue.poll() else null
      }
      if (n > 0) delivered.addAndGet(n.toLong)
      n
    }

    /** Entries waiting. */
    def pending: Int = queue.size

    /** Whether the reader still listens. */
    def isOpen: Boolean = open

    /** Parks the calling thread (the reader's) until `entries` (at least 1) wait, [[close]] is called or `nanos` pass;
      * at once when they already wait.
      */
    def await(nanos: Long, entries: Int = 1): Unit = {
      wakeAt = math.max(1, entries)
      waiter.set(Thread.currentThread())
      // After the waiter is set: an offer before this check is seen here, one after it unparks.
      if (queue.size < wakeAt && open) LockSupport.parkNanos(nanos)
      waiter.set(null)
    }

    def stats: TapReaderStats = TapReaderStats(name, delivered.get, dropped.get)

    /** Leaves the tap; what waits can still be drained. */
    def close(): Unit = {
      open = false
      tap.remove(this)
      val w = waiter.getAndSet(null)
      if (w ne null) LockSupport.unpark(w)
    }
  }
}

/** A bounded queue for many producers and one consumer without a lock (a ring of slots, each with a sequence number
  * telling whose turn it is): an offer never waits for the consumer nor parks behind it, as a queue with a lock can; a
  * full ring refuses. Holds `capacity` rounded up to a power of two.
  */
private[tap] final class RingQueue[A <: AnyRef](capacity: Int) {
  require(capacity >= 1 && capacity <= (1 << 30), "a ring holds 1 to 2^30 entries")
  private val ringSize = Integer.highestOneBit(math.max(1, capacity * 2 - 1))
  private val mask = ringSize - 1L
  private val slots = new AtomicReferenceArray[A](ringSize)
  // Slot i holds the position a producer may fill next (i, i + size, ...) or, once filled, that position + 1.
  private val turns = {
    val t = new AtomicLongArray(ringSize)
    (0 until ringSize).foreach(i => t.set(i, i.toLong))
    t
  }
  private val tail = new AtomicLong
  // Written by the consumer only; volatile so `size` can be read from any thread.
  @volatile private var head = 0L

  /** Adds `a` unless the ring is full; any thread. */
  def offer(a: A): Boolean = {
    var pos = tail.get
    while (true) {
      val i = (pos & mask).toInt
      val gap = turns.get(i) - pos
      if (gap == 0) {
        if (tail.compareAndSet(pos, pos + 1)) {
          slots.lazySet(i, a)
          turns.set(i, pos + 1)
          return true
        } else pos = tail.get
      } else if (gap < 0) return false // the slot still holds the entry of one lap before: full
      else pos = tail.get
    }
    false
  }

  /** The oldest entry, or null when none is ready; the consumer's thread only. */
  def poll(): A = {
    val pos = head
    val i = (pos & mask).toInt
    if (turns.get(i) != pos + 1) null.asInstanceOf[A]
    else {
      val a = slots.get(i)
      slots.lazySet(i, null.asInstanceOf[A])
      turns.set(i, pos + ringSize)
      head = pos + 1
      a
    }
  }

  /** Whether nothing is ready for the consumer. */
  def isEmpty: Boolean = turns.get((head & mask).toInt) != head + 1

  /** Entries offered and not yet taken (a moment's figure). */
  def size: Int = math.max(0L, tail.get - head).toInt
}
