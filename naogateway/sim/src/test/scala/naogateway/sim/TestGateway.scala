package naogateway.sim

import java.net.{InetAddress, InetSocketAddress, StandardProtocolFamily, StandardSocketOptions}
import java.nio.ByteBuffer
import java.nio.channels.{DatagramChannel, SelectionKey, Selector}

import scala.concurrent.duration._

import naogateway.wire.{FrameHeader, MessageContents, RpcCall, RpcReply, RpcValue}

/** A datagram the test gateway received, with its source. */
final case class Heard(bytes: Array[Byte], from: InetSocketAddress) {

  /** The FU-Remote frame it carries, if it is one. */
  def frame: Option[(FrameHeader, MessageContents)] = MessageContents.decodeFrame(bytes).toOption

  /** Its contents, if it is an FU-Remote frame. */
  def contents: Option[MessageContents] = frame.map(_._2)
}

/** A plain UDP socket on 127.0.0.1 standing in for the gateway: every read waits at most until its deadline. */
final class TestGateway extends AutoCloseable {
  private val channel = DatagramChannel.open(StandardProtocolFamily.INET)
  channel.setOption[Integer](StandardSocketOptions.SO_RCVBUF, 4 * 1024 * 1024)
  channel.bind(new InetSocketAddress(InetAddress.getLoopbackAddress, 0))
  channel.configureBlocking(false)
  private val selector = Selector.open()
  channel.register(selector, SelectionKey.OP_READ)
  private val buffer = ByteBuffer.allocate(65536)
  private var nextCallId = 1L

  /** Where robots send to. */
  val address: InetSocketAddress = channel.getLocalAddress.asInstanceOf[InetSocketAddress]

  /** Sends one datagram. */
  def send(bytes: Array[Byte], to: InetSocketAddress): Unit = {
    channel.send(ByteBuffer.wrap(bytes), to)
    ()
  }

  /** The next datagram, if one arrives within `within`. */
  def receive(within: FiniteDuration): Option[Heard] = {
    val deadline = within.fromNow
    var heard = poll()
    while (heard.isEmpty && deadline.hasTimeLeft()) {
      selector.select(math.max(1L, deadline.timeLeft.toMillis))
      selector.selectedKeys().clear()
      heard = poll()
    }
    heard
  }

  /** Everything that arrives during `window`. */
  def collectFor(window: FiniteDuration): Vector[Heard] = {
    val deadline = window.fromNow
    val out = Vector.newBuilder[Heard]
    while (deadline.hasTimeLeft()) receive(deadline.timeLeft).foreach(out += _)
    out.result()
  }

  /** The first datagram within `within` for which `pick` gives a value; the others are dropped. */
  def await[A](within: FiniteDuration)(pick: Heard => Option[A]): Option[A] = {
    val deadline = within.fromNow
    var found = Option.empty[A]
    while (found.isEmpty && deadline.hasTimeLeft()) found = receive(deadline.timeLeft).flatMap(pick)
    found
  }

  /** Drops whatever has arrived so far. */
  def drain(): Unit = while (poll().isDefined) ()

  /** Calls `module.method` on the robot at `robot` and waits for the reply with the call's id. */
  def call(robot: InetSocketAddress, module: String, method: String, params: RpcValue*): Option[(RpcReply, Heard)] = {
    val id = nextCallId
    nextCallId += 1
    send(TestGateway.request(module, method, params.toVector, id), robot)
    await(5.seconds) { heard =>
      heard.contents.flatMap(_.rpcResponse).map(RpcReply.fromProto).filter(_.callId.contains(id)).map(_ -> heard)
    }
  }

  private def poll(): Option[Heard] = {
    buffer.clear()
    Option(channel.receive(buffer)).map { from =>
      buffer.flip()
      val bytes = new Array[Byte](buffer.remaining())
      buffer.get(bytes)
      Heard(bytes, from.asInstanceOf[InetSocketAddress])
    }
  }

  override def close(): Unit = {
    selector.close()
    channel.close()
  }
}

/** Frames the tests send. */
object TestGateway {

  /** An RPC request frame, legacy header. */
  def request(module: String, method: String, params: Vector[RpcValue], callId: Long): Array[Byte] =
    MessageContents
      .encodeFrame(MessageContents(0, rpcRequest = Some(RpcCall(module, method, params, Some(callId)).toProto)))
      .fold(e => throw new IllegalArgumentException(e.describe), identity)
}
