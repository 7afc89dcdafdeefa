package naogateway.gateway.robot

import java.util.concurrent.atomic.AtomicLong

/** What left for one robot, counted where it is sent: the robot's sender adds each frame as it hands it to the outbox,
  * and the robot actor, which creates the count and outlives its sender's restarts, reads it for the link figures. No
  * message per datagram: the count is two atomic adds.
  */
private[naogateway] final class SentFigures {
  private val frames = new AtomicLong
  private val total = new AtomicLong

  /** A frame of `bytes` left for the robot. */
  def sent(bytes: Int): Unit = {
    frames.incrementAndGet()
    total.addAndGet(bytes.toLong)
  }

  /** Frames sent so far. */
  def datagrams: Long = frames.get

  /** Bytes sent so far. */
  def bytes: Long = total.get
}
