package bench

import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.{ClosedChannelException, DatagramChannel}

import scala.concurrent.duration.FiniteDuration

import naogateway.proto.{Response, Status}
import naogateway.testkit.TestLoopback
import naogateway.wire.{FrameSigning, FumanoidsFrame, MessageContents, ReplayWindow, RobotKey, SignedLink}

/** Robot 1 as a bare UDP responder on a loopback address of its own, port 3838: one thread answers every request frame
  * at once with a reply of the same call id, another sends a keep-alive every 200 ms. No simulator. With `key` it signs
  * as protocol.md 6.7 says (boot epoch 1, its frames in the order they leave) and acts only on the gateway's frames
  * that verify and pass its window, as a signing firmware does.
  */
private[bench] final class PlainRobot(gateway: InetSocketAddress, closeAfter: FiniteDuration,
    key: Option[RobotKey] = None) {
  private val socket = DatagramChannel.open()
    .bind(new InetSocketAddress(TestLoopback.address(), naogateway.sim.SimulatedRobot.ReceivePort))
  private val watchdog = GatewayBench.closeAfter(closeAfter, socket)
  private val keepAlive = MessageContents
    .encodeFrame(MessageContents(1, status = Some(Status(teamID = Some(1), activeAgent = Some("PlainRobot")))))
    .fold(e => throw new IllegalStateException(e.describe), identity)
  private val Epoch = 1L
  // Guarded by `this`: the frame counter and the gateway's window, so frames leave in their timestamp's order.
  private var counter = 0L
  private var window = ReplayWindow.empty

  /** `frame` sent to `to`, signed first when the robot signs. */
  private def send(frame: Array[Byte], to: InetSocketAddress): Unit = key match {
    case None => socket.send(ByteBuffer.wrap(frame), to); ()
    case Some(k) =>
      synchronized {
        val signed = FrameSigning.signEncoded(frame, k, SignedLink.FromRobot(1),
          FrameSigning.robotTimestamp(Epoch, counter))
        counter += 1
        signed.foreach(b => socket.send(ByteBuffer.wrap(b), to))
      }
  }

  /** Whether a frame from the gateway counts: always without a key, else only signed, in this epoch, and newer. */
  private def accepted(frame: Array[Byte]): Boolean = key.forall { k =>
    FumanoidsFrame.decodeHeader(frame).toOption.exists { header =>
      FrameSigning.verifyFrame(frame, header, k, SignedLink.ToRobot(1, Epoch.toInt)).toOption.exists { body =>
        synchronized {
          window.accept(body.timestamp) match {
            case Right(next) => window = next; true
            case Left(_)     => false
          }
        }
      }
    }
  }

  private val beats = new Thread(
    () => {
      try while (socket.isOpen) { send(keepAlive, gateway); Thread.sleep(200) }
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
          MessageContents.decodeFrame(bytes).toOption.filter(_ => accepted(bytes)).flatMap(_._2.rpcRequest).foreach {
            request =>
              val answer = Response(returnval = Some(naogateway.wire.RpcValue.UInt(0).toProto), callId = request.callId)
              val reply = MessageContents(1, rpcResponse = Some(answer))
              MessageContents.encodeFrame(reply).foreach(b => send(b, from.asInstanceOf[InetSocketAddress]))
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
