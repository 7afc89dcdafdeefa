package naogateway.sim

import naogateway.wire.stream.{SecureStream, StreamSettings}

/** The robot's end of the secure stream as a [[SimulatedRobot]] runs it: the gateway's own pure [[SecureStream]] behind
  * the [[RobotStream]] hook, so the simulated robot speaks exactly the protocol of docs/protocol.md §11.
  *
  * `Transmit` becomes [[RobotStream.Step.transmit]] and `Deliver` becomes [[RobotStream.Step.deliver]]. The robot does
  * not care whether the gateway received its replies (the thesis firmware has no way to report it either), so
  * `Acknowledged` and `Expired` are dropped, and a reply the endpoint refuses (its send queue is full) is dropped as
  * the hook's contract allows. Build fresh endpoints with [[SecureStreamRobotStream.factory]].
  *
  * @param state
  *   the pure endpoint
  * @param nextId
  *   the id the next reply is sent with; ids only have to be distinct while unacknowledged
  * @param refused
  *   replies the endpoint refused so far
  */
final case class SecureStreamRobotStream(state: SecureStream, nextId: Long = 0L, refused: Long = 0L)
    extends RobotStream {

  def receive(segment: Array[Byte], now: Long): RobotStream.Step = stepped(state.receive(segment, now), nextId)

  def send(frame: Array[Byte], now: Long): RobotStream.Step =
    state.send(frame, nextId, None, now) match {
      case Right(step) => stepped(step, nextId + 1)
      case Left(_)     => RobotStream.Step(copy(refused = refused + 1), Vector.empty, Vector.empty)
    }

  def tick(now: Long): RobotStream.Step = stepped(state.tick(now), nextId)

  def nextTimerAt: Option[Long] = state.nextTimerAt

  private def stepped(step: SecureStream.Step, id: Long): RobotStream.Step = {
    val transmit = Vector.newBuilder[Array[Byte]]
    val deliver = Vector.newBuilder[Array[Byte]]
    step.outputs.foreach {
      case SecureStream.Transmit(datagram)                        => transmit += datagram
      case SecureStream.Deliver(payload)                          => deliver += payload
      case SecureStream.Acknowledged(_) | SecureStream.Expired(_) => ()
    }
    RobotStream.Step(copy(state = step.state, nextId = id), transmit.result(), deliver.result())
  }
}

/** Factories of [[SecureStreamRobotStream]]. */
object SecureStreamRobotStream {

  /** A fresh endpoint (first data segment 0, ACK byte maxSeq) for every boot, with `settings`; the default is the
    * thesis firmware's stop-and-wait over 0..20. The gateway's end must use the same window and maxSeq.
    */
  def factory(settings: StreamSettings = StreamSettings.thesis): RobotStream.Factory =
    now => SecureStreamRobotStream(SecureStream.initial(settings, now))
}
