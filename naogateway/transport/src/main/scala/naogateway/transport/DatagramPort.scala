package naogateway.transport

import java.io.IOException
import java.net.{InetSocketAddress, StandardSocketOptions}
import java.nio.ByteBuffer
import java.nio.channels.{ClosedChannelException, ClosedSelectorException, DatagramChannel, SelectionKey, Selector}
import java.util.concurrent.Executor
import java.util.concurrent.locks.LockSupport

import scala.util.control.NonFatal

import org.slf4j.LoggerFactory

/** Writes one datagram without blocking; false when it was not sent (kernel buffer full, port closed, send failed). */
trait DatagramWriter {

  /** Sends `bytes` to `to` now, or not at all. */
  def send(bytes: Array[Byte], to: InetSocketAddress): Boolean
}

/** A UDP port: one non-blocking `DatagramChannel`, read on the thread of the dispatcher it is started on when that runs
  * on a [[PortLoop]] ([[DatagramPort.startOn]]), or by a dedicated daemon thread ([[DatagramPort.start]]), and written
  * by whoever holds the port. The gateway's robot port and the apps' datagram door are each one.
  *
  * Why a loop or a thread and not an actor: a datagram read by Akka IO passes its selector actor and a link actor
  * before any code of ours sees it, two mailboxes per datagram each way. The port is read where a selector waits, never
  * inside an actor, and each datagram goes to a [[DatagramPort.Handler]] on that same thread. Writes need no thread of
  * their own: a non-blocking send either takes the datagram or returns 0 at once.
  */
final class DatagramPort private (private[naogateway] val channel: DatagramChannel, threadName: String)
    extends DatagramWriter
    with PortLoop.Source {
  import DatagramPort._

  @volatile private var open = true
  // Who reads the port; changed under the port's lock, acted on outside it (a detach waits for the loop's thread).
  private var reading: Reading = NotStarted
  @volatile private var handler: Handler = null
  private var failures = 0L

  /** Where the port is bound (the real port when 0 was asked for). */
  val localAddress: InetSocketAddress = channel.getLocalAddress.asInstanceOf[InetSocketAddress]

  def send(bytes: Array[Byte], to: InetSocketAddress): Boolean =
    try channel.send(ByteBuffer.wrap(bytes), to) > 0 || bytes.isEmpty
    catch { case _: IOException => false } // closed, or the kernel refused the destination: the datagram is dropped

  /** Starts the reader thread with `handler`; once only. */
  def start(handler: Handler): Unit = {
    val started = synchronized {
      require(reading == NotStarted, "the port's reader runs already")
      this.handler = handler
      ownThread()
    }
    started.start()
  }

  /** Reads the port on `executor`'s thread when that is a [[PortLoop]]'s (so a datagram wakes one thread, the one that
    * runs its actors, not two); on any other executor with a reader thread of its own, as [[start]]. Once only.
    */
  def startOn(handler: Handler, executor: Executor): Unit = {
    synchronized {
      require(reading == NotStarted, "the port's reader runs already")
      this.handler = handler
      reading = Starting
    }
    executor.execute { () =>
      val thread = synchronized {
        // Closed before this ran: nothing to start.
        if (reading != Starting) None
        else
          PortLoop.current match {
            case Some(loop) =>
              reading = Attached(loop.attach(this))
              None
            case None => Some(ownThread())
          }
      }
      thread.foreach(_.start())
    }
  }

  // Under the port's lock; the caller starts the thread outside it.
  private def ownThread(): Thread = {
    val selector = Selector.open()
    try channel.register(selector, SelectionKey.OP_READ)
    catch {
      case NonFatal(e) =>
        selector.close()
        throw e
    }
    val thread = new Thread(() => readLoop(selector), threadName)
    thread.setDaemon(true)
    reading = OwnThread(thread, selector)
    thread
  }

  /** Stops the reading (waiting at most `joinMillis` for the reader, never for the calling thread itself) and closes
    * the channel; once it returns the handler is not called any more. Safe to call more than once.
    */
  def close(joinMillis: Long): Unit = {
    open = false
    val was = synchronized {
      val r = reading
      reading = Closed
      r
    }
    try
      was match {
        case Attached(attachment) =>
          if (!attachment.detach(joinMillis))
            log.warn("Port {}: its loop did not let it go within {} ms", localAddress, joinMillis)
        case OwnThread(thread, selector) =>
          try selector.wakeup()
          catch { case NonFatal(_) => () }
          if (thread ne Thread.currentThread()) thread.join(joinMillis)
        case _ => ()
      }
    finally
      try channel.close()
      finally
        was match {
          case OwnThread(_, selector) => selector.close()
          case _                      => ()
        }
  }

  /** Whether the port's own reader thread is running (false on a loop). */
  def readerAlive: Boolean = synchronized {
    reading match {
      case OwnThread(thread, _) => thread.isAlive
      case _                    => false
    }
  }

  /** Whether the port is read on a [[PortLoop]]. */
  def onLoop: Boolean = synchronized {
    reading match {
      case Attached(_) => true
      case _           => false
    }
  }

  private def readLoop(selector: Selector): Unit = {
    // One buffer for the port's whole life; each datagram is copied out at its own size.
    val buffer = ByteBuffer.allocateDirect(MaxDatagramBytes)
    try {
      while (open) {
        selector.select()
        selector.selectedKeys().clear()
        drain(buffer, Int.MaxValue)
      }
    } catch {
      case _: ClosedChannelException | _: ClosedSelectorException => () // closed by close(): the normal end
    }
  }

  /** Reads at most `max` datagrams (on the one thread that reads the port), then tells the handler it caught up if the
    * channel is empty.
    */
  private[naogateway] def drain(buffer: ByteBuffer, max: Int): Unit = {
    var left = max
    while (left > 0 && open) {
      buffer.clear()
      val from =
        try channel.receive(buffer).asInstanceOf[InetSocketAddress]
        catch {
          case e: ClosedChannelException => throw e
          case e: IOException =>
            failures += 1
            if (RateLimitedLog.due(failures))
              log.warn("Port {}: receive failed ({} so far): {}", localAddress, failures, e.toString)
            // A failure that repeats must not spin a core.
            LockSupport.parkNanos(1000000L)
            null
        }
      if (from == null) left = -1
      else {
        left -= 1
        buffer.flip()
        val bytes = new Array[Byte](buffer.remaining)
        buffer.get(bytes)
        try handler.received(bytes, from)
        catch {
          case NonFatal(e) =>
            failures += 1
            if (RateLimitedLog.due(failures))
              log.error(s"Port $localAddress: a datagram from $from failed ($failures so far)", e)
        }
      }
    }
    // Empty (or closed from the handler): the handler may flush what it batched. A full batch leaves more to read.
    if (left < 0 || !open) handler.caughtUp()
  }
}

/** Opening a datagram port, and what its reader hands datagrams to. */
object DatagramPort {

  /** Where the reader hands what it reads; called on one thread at a time, the one that reads the port. */
  trait Handler {

    /** One datagram of `bytes` from `from`; `bytes` belongs to the handler. */
    def received(bytes: Array[Byte], from: InetSocketAddress): Unit

    /** Nothing more to read for now: the reader is about to wait. */
    def caughtUp(): Unit
  }

  /** The largest UDP payload; a longer datagram cannot arrive. */
  val MaxDatagramBytes: Int = 65536

  private val log = LoggerFactory.getLogger(classOf[DatagramPort])

  // Who reads the port.
  private sealed trait Reading
  private case object NotStarted extends Reading
  private case object Starting extends Reading
  private final case class OwnThread(thread: Thread, selector: Selector) extends Reading
  private final case class Attached(attachment: PortLoop#Attachment) extends Reading
  private case object Closed extends Reading

  /** A port bound to `address` with a kernel receive buffer of `receiveBufferBytes`; reading starts with
    * [[DatagramPort.start]] or [[DatagramPort.startOn]].
    */
  def open(address: InetSocketAddress, receiveBufferBytes: Int, threadName: String): DatagramPort = {
    val channel = DatagramChannel.open()
    try {
      channel.setOption[Integer](StandardSocketOptions.SO_RCVBUF, receiveBufferBytes)
      channel.bind(address)
      channel.configureBlocking(false)
      new DatagramPort(channel, threadName)
    } catch {
      case NonFatal(e) =>
        channel.close()
        throw e
    }
  }
}
