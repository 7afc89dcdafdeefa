package naogateway.gateway.link

import java.net.InetSocketAddress
import java.util.concurrent.Executor

import scala.annotation.unused

import naogateway.transport.{DatagramPort, DatagramWriter}

/** Where the gateway's robot datagrams come from and go to: the robot port's socket ([[RobotPort]]), or a recording
  * played back ([[ReplayLink]]). Whatever it is, it hands every datagram to one [[RobotPort.Handler]] on one thread.
  */
trait RobotLink extends DatagramWriter {

  /** Where the link receives (the real port when 0 was asked for). */
  def localAddress: InetSocketAddress

  /** Starts handing datagrams to `handler`; once only. */
  def start(handler: RobotPort.Handler): Unit

  /** Starts handing datagrams to `handler`, on `executor`'s thread where the link can (a socket on a [[PortLoop]]); a
    * link that cannot reads as [[start]] does. Once only.
    */
  def startOn(handler: RobotPort.Handler, @unused executor: Executor): Unit = start(handler)

  /** Stops handing datagrams (waiting at most `joinMillis` for the thread) and releases the link; safe to repeat. */
  def close(joinMillis: Long = 2000L): Unit
}

/** The gateway's robot UDP port: a [[DatagramPort]] read on the robot dispatcher's own thread (its [[PortLoop]]), so a
  * robot's answer wakes the thread that runs the robot actors and nothing else; written by whoever holds the port (the
  * outbox, the relay).
  */
final class RobotPort private (port: DatagramPort) extends RobotLink {

  /** Where the port is bound (the real port when 0 was asked for). */
  val localAddress: InetSocketAddress = port.localAddress

  def send(bytes: Array[Byte], to: InetSocketAddress): Boolean = port.send(bytes, to)

  /** Starts the reader thread with `handler`; once only. */
  def start(handler: RobotPort.Handler): Unit = port.start(handler)

  /** Reads the port on `executor`'s thread when that is a [[PortLoop]]'s (the robot dispatcher's); on any other
    * executor with a reader thread of its own, as [[start]]. Once only.
    */
  override def startOn(handler: RobotPort.Handler, executor: Executor): Unit = port.startOn(handler, executor)

  /** Stops the reading (waiting at most `joinMillis` for the reader, never for the calling thread itself) and closes
    * the channel; once it returns the handler is not called any more. Safe to call more than once.
    */
  def close(joinMillis: Long): Unit = port.close(joinMillis)

  /** Whether the port's own reader thread is running (false on a loop). */
  def readerAlive: Boolean = port.readerAlive

  /** Whether the port is read on a [[PortLoop]]. */
  def onLoop: Boolean = port.onLoop
}

/** Opening the robot port. */
object RobotPort {

  /** Where the reader hands what it reads; called on one thread at a time, the one that reads the port. */
  trait Handler extends DatagramPort.Handler {

    /** A GameController packet from `from`. The robot port never calls it (the GameController has a socket of its own);
      * a replayed recording does, so the game states come back through the gateway's usual handling.
      */
    def gameControllerReceived(bytes: Array[Byte], from: InetSocketAddress): Unit
  }

  /** The largest UDP payload; a longer datagram cannot arrive. */
  val MaxDatagramBytes: Int = DatagramPort.MaxDatagramBytes

  /** A port bound to `address` with a kernel receive buffer of `receiveBufferBytes`; reading starts with
    * [[RobotPort.start]] or [[RobotPort.startOn]].
    */
  def open(address: InetSocketAddress, receiveBufferBytes: Int, threadName: String): RobotPort =
    new RobotPort(DatagramPort.open(address, receiveBufferBytes, threadName))
}
