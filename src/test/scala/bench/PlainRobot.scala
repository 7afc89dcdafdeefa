package bench

import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.{ClosedChannelException, DatagramChannel}

import scala.concurrent.duration.FiniteDuration

import naogateway.proto.{Response, Status}
import naogateway.testkit.TestLoopback
import naogateway.wire.MessageContents

/** Robot 1 as a bare UDP responder on a loopback address of its own, port 3838: one thread answers every request frame
  * at once with a reply of the same call id, another sends a keep-alive every 200 ms. No simulator.
  */
private[bench] final class PlainRobot(gateway: InetSocketAddress, closeAfter: FiniteDuration) {
  private val socket = DatagramChannel.open()
    .bind(new InetSocketAddress(TestLoopback.address(), naogateway.sim.SimulatedRobot.ReceivePort))
  private val watchdog = GatewayBench.closeAfter(closeAfter, socket)
  private val keepAlive = MessageContents
    .encodeFrame(MessageContents(1, status = Some(Status(teamID = Some(1), activeAgent = Some("PlainRobot")))))
    .fold(e => throw new IllegalStateException(e.describe), identity)
  private val beats = new Thread(
    () => {
      try while (socket.isOpen) { socket.send(ByteBuffer.wrap(keepAlive), gateway); Thread.sleep(200) }
      catch { case _: ClosedChannelException | _: InterruptedException => () }
    },
    "plain-robot-keep-alive"
  )
  private val answers = new Thread(
    () => {
      val in = ByteBuffer.allocate(2048)
      try
        while (socket.isOpen) {
          in.clear()
          val from = socket.receive(in)
          in.flip()
          val bytes = new Array[Byte](in.remaining)
          in.get(bytes)
          MessageContents.decodeFrame(bytes).toOption.flatMap(_._2.rpcRequest).foreach { request =>
            val answer = Response(returnval = Some(naogateway.wire.RpcValue.UInt(0).toProto), callId = request.callId)
            val reply = MessageContents(1, rpcResponse = Some(answer))
            MessageContents.encodeFrame(reply).foreach(b => socket.send(ByteBuffer.wrap(b), from))
          }
        }
      catch { case _: ClosedChannelException => () }
    },
    "plain-robot-answers"
  )
  Seq(beats, answers).foreach { t => t.setDaemon(true); t.start() }

  def close(): Unit = {
    socket.close()
    beats.interrupt()
    answers.join(5000)
    watchdog.shutdownNow()
    ()
  }
}
