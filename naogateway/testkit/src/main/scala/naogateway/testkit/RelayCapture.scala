package naogateway.testkit

import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration.FiniteDuration

import naogateway.wire.MessageContents

/** Real frames of a robot, caught where the gateway's FU-Remote relay sends its byte-identical copies: material for
  * replays.
  */
object RelayCapture {

  /** The frames of robot `robotId` the relay passes to `recorder` within `window` (polling; the window bounds it). It
    * blocks its caller for `window`: a spec's own thread, never an actor's (the test kit is for specs only).
    */
  def frames(recorder: DatagramChannel, robotId: Int, window: FiniteDuration): Vector[Array[Byte]] = {
    recorder.configureBlocking(false)
    val buffer = ByteBuffer.allocate(2048)
    val deadline = window.fromNow
    var frames = Vector.empty[Array[Byte]]
    while (deadline.hasTimeLeft()) {
      buffer.clear()
      if (recorder.receive(buffer) == null) Thread.sleep(5)
      else {
        buffer.flip()
        val bytes = new Array[Byte](buffer.remaining)
        buffer.get(bytes)
        if (MessageContents.decodeFrame(bytes).exists(_._2.robotId == robotId)) frames :+= bytes
      }
    }
    frames
  }
}
