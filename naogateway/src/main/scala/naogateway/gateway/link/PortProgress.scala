package naogateway.gateway.link

/** Whether the robot port's reader is behind, for the heartbeats: it is from the first datagram it reads after it found
  * the socket empty until it finds it empty again. A probe whose timeout came while the reader was behind may have its
  * answer (or a keep-alive) still waiting in the socket behind a burst; one whose timeout came while the reader had
  * nothing left to read, or before it last found the socket empty, is a miss. Written by the reader's one thread, read
  * by the robots' heartbeats.
  */
private[naogateway] class PortProgress(clock: () => Long = () => System.nanoTime()) {
  @volatile private var emptyAt = clock()
  @volatile private var behind = false

  /** The reader read a datagram. */
  def reading(): Unit = if (!behind) behind = true

  /** The reader found the socket empty now. */
  def caughtUp(): Unit = {
    emptyAt = clock()
    behind = false
  }

  /** Whether the reader has nothing left to read, or found the socket empty at or after `nanos` (on the same clock). */
  def caughtUpSince(nanos: Long): Boolean = !behind || emptyAt - nanos >= 0
}

/** The progress of a port with nothing to catch up with. */
private[naogateway] object PortProgress {

  /** Never behind: for a robot no datagram port carries (a ZeroMQ robot) and a robot actor on its own (tests). */
  val Always: PortProgress = new PortProgress() {
    override def caughtUpSince(nanos: Long): Boolean = true
  }
}
