package naogateway.testkit

import java.nio.ByteBuffer
import java.nio.channels.{DatagramChannel, SelectionKey, Selector}

import scala.concurrent.duration.FiniteDuration

import naogateway.wire.MessageContents

/** Real frames of a robot, caught where the gateway's FU-Remote relay sends its byte-identical copies: material for
  * replays.
  */
object RelayCapture {

  /** The frames of robot `robotId` the relay passes to `recorder` within `window`. It returns when the window ends, so
    * it holds its caller that long: call it from a spec's own thread, never an actor's (the test kit is for specs
    * only). It waits on a selector for each datagram, neither polling nor sleeping.
    */
  def frames(recorder: DatagramChannel, robotId: Int, window: FiniteDuration): Vector[Array[Byte]] = {
    recorder.configureBlocking(false)
    val selector = Selector.open()
    try {
      recorder.register(selector, SelectionKey.OP_READ)
      val buffer = ByteBuffer.allocate(2048)
      val deadline = window.fromNow
      var frames = Vector.empty[Array[Byte]]
      while (deadline.hasTimeLeft()) {
        buffer.clear()
        if (recorder.receive(buffer) == null) {
          selector.select(math.max(1L, deadline.timeLeft.toMillis))
          selector.selectedKeys().clear()
        } else {
          buffer.flip()
          val bytes = new Array[Byte](buffer.remaining)
          buffer.get(bytes)
          if (MessageContents.decodeFrame(bytes).exists(_._2.robotId == robotId)) frames :+= bytes
        }
      }
      frames
    } finally selector.close()
  }
}
