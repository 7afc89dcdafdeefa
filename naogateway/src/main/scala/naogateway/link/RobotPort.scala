package naogateway.link

import java.io.IOException
import java.net.{InetSocketAddress, StandardSocketOptions}
import java.nio.ByteBuffer
import java.nio.channels.{ClosedChannelException, ClosedSelectorException, DatagramChannel, SelectionKey, Selector}
import java.util.concurrent.locks.LockSupport

import scala.util.control.NonFatal

import org.slf4j.LoggerFactory

import naogateway.RateLimitedLog

/** Writes one datagram without blocking; false when it was not sent (kernel buffer full, port closed, send failed). */
trait DatagramWriter {

  /** Sends `bytes` to `to` now, or not at all. */
  def send(bytes: Array[Byte], to: InetSocketAddress): Boolean
}

/** Where the gateway's robot datagrams come from and go to: the robot port's socket ([[RobotPort]]), or a recording
  * played back ([[ReplayLink]]). Whatever it is, it hands every datagram to one [[RobotPort.Handler]] on one thread.
  */
trait RobotLink extends DatagramWriter {

  /** Where the link receives (the real port when 0 was asked for). */
  def localAddress: InetSocketAddress

  /** Starts handing datagrams to `handler`; once only. */
  def start(handler: RobotPort.Handler): Unit

  /** Stops handing datagrams (waiting at most `joinMillis` for the thread) and releases the link; safe to repeat. */
  def close(joinMillis: Long = 2000L): Unit
}

/** The gateway's robot UDP port: one non-blocking `DatagramChannel`, read by a dedicated daemon thread and written by
  * whoever holds the port (the outbox, the relay).
  *
  * Why a thread and not an actor: a datagram read by Akka IO passes its selector actor and a link actor before any
  * gateway code sees it, two mailboxes per datagram each way. The reader thread blocks in its own selector only, never
  * inside an actor, and hands each datagram to a [[RobotPort.Handler]] (the gateway's routing) on that same thread.
  * Writes need no thread of their own: a non-blocking send either takes the datagram or returns 0 at once.
  */
final class RobotPort private (channel: DatagramChannel, threadName: String) extends RobotLink {
  import RobotPort._

  private val selector = Selector.open()
  channel.register(selector, SelectionKey.OP_READ)
  @volatile private var open = true
  @volatile private var reader: Option[Thread] = None

  /** Where the port is bound (the real port when 0 was asked for). */
  val localAddress: InetSocketAddress = channel.getLocalAddress.asInstanceOf[InetSocketAddress]

  def send(bytes: Array[Byte], to: InetSocketAddress): Boolean =
    try channel.send(ByteBuffer.wrap(bytes), to) > 0 || bytes.isEmpty
    catch { case _: IOException => false } // closed, or the kernel refused the destination: the datagram is dropped

  /** Starts the reader thread with `handler`; once only. */
  def start(handler: Handler): Unit = synchronized {
    require(reader.isEmpty, "the robot port's reader runs already")
    val thread = new Thread(() => readLoop(handler), threadName)
    thread.setDaemon(true)
    reader = Some(thread)
    thread.start()
  }

  /** Stops the reader (waiting at most `joinMillis` for it) and closes the channel; safe to call more than once. */
  def close(joinMillis: Long): Unit = {
    open = false
    try selector.wakeup()
    catch { case NonFatal(_) => () }
    reader.foreach(t => if (t ne Thread.currentThread()) t.join(joinMillis))
    try channel.close()
    finally selector.close()
  }

  /** Whether the reader thread is running. */
  def readerAlive: Boolean = reader.exists(_.isAlive)

  private def readLoop(handler: Handler): Unit = {
    // One buffer for the port's whole life; each datagram is copied out at its own size.
    val buffer = ByteBuffer.allocateDirect(MaxDatagramBytes)
    var failures = 0L
    try {
      while (open) {
        selector.select()
        selector.selectedKeys().clear()
        var more = open
        while (more) {
          buffer.clear()
          val from =
            try channel.receive(buffer).asInstanceOf[InetSocketAddress]
            catch {
              case e: ClosedChannelException => throw e
              case e: IOException =>
                failures += 1
                if (RateLimitedLog.due(failures))
                  log.warn("Robot port {}: receive failed ({} so far): {}", localAddress, failures, e.toString)
                // A failure that repeats must not spin a core.
                LockSupport.parkNanos(1000000L)
                null
            }
          if (from == null) more = false
          else {
            buffer.flip()
            val bytes = new Array[Byte](buffer.remaining)
            buffer.get(bytes)
            try handler.received(bytes, from)
            catch {
              case NonFatal(e) =>
                failures += 1
                if (RateLimitedLog.due(failures))
                  log.error(s"Robot port $localAddress: a datagram from $from failed ($failures so far)", e)
            }
          }
        }
        handler.caughtUp()
      }
    } catch {
      case _: ClosedChannelException | _: ClosedSelectorException => () // closed by close(): the normal end
    }
  }
}

/** Opening the robot port. */
object RobotPort {

  /** Where the reader hands what it reads; called on the reader thread only. */
  trait Handler {

    /** One datagram of `bytes` from `from`; `bytes` belongs to the handler. */
    def received(bytes: Array[Byte], from: InetSocketAddress): Unit

    /** Nothing more to read for now: the reader is about to wait. */
    def caughtUp(): Unit

    /** A GameController packet from `from`. The robot port never calls it (the GameController has a socket of its own);
      * a replayed recording does, so the game states come back through the gateway's usual handling.
      */
    def gameControllerReceived(bytes: Array[Byte], from: InetSocketAddress): Unit
  }

  /** The largest UDP payload; a longer datagram cannot arrive. */
  val MaxDatagramBytes: Int = 65536

  private val log = LoggerFactory.getLogger(classOf[RobotPort])

  /** A port bound to `address` with a kernel receive buffer of `receiveBufferBytes`; the reader starts with
    * [[RobotPort.start]].
    */
  def open(address: InetSocketAddress, receiveBufferBytes: Int, threadName: String): RobotPort = {
    val channel = DatagramChannel.open()
    try {
      channel.setOption[Integer](StandardSocketOptions.SO_RCVBUF, receiveBufferBytes)
      channel.bind(address)
      channel.configureBlocking(false)
      new RobotPort(channel, threadName)
    } catch {
      case NonFatal(e) =>
        channel.close()
        throw e
    }
  }
}
