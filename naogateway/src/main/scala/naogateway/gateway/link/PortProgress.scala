package naogateway.gateway.link

/** When the robot port's reader last found its socket empty, for the heartbeats: a probe whose timeout came before that
  * moment is a miss, but one whose timeout came since may have its answer (or a keep-alive) still waiting in the socket
  * behind a burst the reader has not caught up with. Written by the reader's one thread, read by the robots'
  * heartbeats.
  */
private[naogateway] class PortProgress(clock: () => Long = () => System.nanoTime()) {
  @volatile private var emptyAt = clock()

  /** The reader found the socket empty now. */
  def caughtUp(): Unit = emptyAt = clock()

  /** Whether the reader found the socket empty at or after `nanos` (on the same clock). */
  def caughtUpSince(nanos: Long): Boolean = emptyAt - nanos >= 0
}

/** The progress of a port with nothing to catch up with. */
private[naogateway] object PortProgress {

  /** Never behind: for a robot no datagram port carries (a ZeroMQ robot) and a robot actor on its own (tests). */
  val Always: PortProgress = new PortProgress() {
    override def caughtUpSince(nanos: Long): Boolean = true
  }
}
