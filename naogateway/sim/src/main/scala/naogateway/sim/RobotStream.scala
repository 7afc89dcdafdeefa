package naogateway.sim

/** The robot's end of the secure stream (docs/protocol.md §11), as a [[SimulatedRobot]] plugs it in: a pure state
  * machine in the robot's clock (nanoseconds), like [[RobotFirmware]].
  *
  * The robot hands it every datagram classified as a stream segment, transmits what it returns (to the gateway's
  * address, which is where segments from the robot go), treats every delivered payload as one FU-Remote frame from the
  * gateway, and sends the replies to those frames back through [[send]] (a reply goes back the way its request came,
  * §7.1). It calls [[tick]] when [[nextTimerAt]] has come. After a power cycle or `system.reset` the robot builds a
  * fresh endpoint with its [[RobotStream.Factory]], so sequence numbers start afresh (§11.3).
  *
  * An adapter over the pure `SecureStream` state machine needs only to map its outputs: `Transmit` to
  * [[RobotStream.Step.transmit]], `Deliver` to [[RobotStream.Step.deliver]], and drop the rest.
  */
trait RobotStream {

  /** Takes one segment from the gateway, header included. */
  def receive(segment: Array[Byte], now: Long): RobotStream.Step

  /** Offers one whole FU-Remote frame for reliable delivery to the gateway; an endpoint that refuses it drops it. */
  def send(frame: Array[Byte], now: Long): RobotStream.Step

  /** Does whatever is due at `now` (retransmission, idle ACK); calling it early is harmless. */
  def tick(now: Long): RobotStream.Step

  /** When [[tick]] must be called next, if ever. */
  def nextTimerAt: Option[Long]
}

/** The hook's types. */
object RobotStream {

  /** The endpoint after a transition, the segments to transmit and the payloads delivered in order. */
  final case class Step(stream: RobotStream, transmit: Vector[Array[Byte]], deliver: Vector[Array[Byte]])

  /** Builds a fresh endpoint (initial sequence state) at the robot's boot time `now`. */
  type Factory = Long => RobotStream
}
