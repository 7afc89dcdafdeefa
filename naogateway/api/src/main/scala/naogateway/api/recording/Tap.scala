package naogateway.api.recording

import java.net.InetSocketAddress

import naogateway.proto.RecordedPort
import naogateway.wire.MessageContents

/** One thing that crossed the gateway's ports, as its tap publishes it: built once, shared by every reader, never
  * changed (a datagram's bytes are the port's own array: readers must not write to it).
  */
sealed trait Tapped {

  /** `System.nanoTime` when it was published. */
  def nanoTime: Long
}

/** What the tap publishes. */
object Tapped {

  /** A datagram that passed `port`, `received` or sent, byte for byte; `robotId` the robot at the far end (-1: none).
    * `decoded`: the FU-Remote frame as the gateway decoded it when it received it, so that no reader decodes it again
    * (None when it was not a frame the gateway could decode, or it was not decoded: sent datagrams).
    */
  final case class Datagram(nanoTime: Long, port: RecordedPort, received: Boolean, source: InetSocketAddress,
      destination: InetSocketAddress, bytes: Array[Byte], robotId: Int, decoded: Option[MessageContents] = None)
      extends Tapped

  /** A decision of the gateway. */
  final case class Decided(nanoTime: Long, decision: Decision) extends Tapped
}

/** One reader's figures: what it was handed and what it lost because it was behind (its queue was full). */
final case class TapReaderStats(reader: String, delivered: Long, dropped: Long)

/** A reader's place at the tap: a bounded queue of its own, filled by the gateway's threads and emptied by the reader.
  * The gateway never waits for it: what does not fit is dropped and counted for this reader alone.
  */
trait TapSubscription {

  /** Moves up to `max` waiting entries into `into` (in the order they were published); answers how many. */
  def drainTo(into: java.util.Collection[_ >: Tapped], max: Int): Int

  /** This reader's figures so far. */
  def stats: TapReaderStats

  /** Leaves the tap: nothing more is queued, and with no reader left the gateway builds nothing. */
  def close(): Unit
}

/** The gateway's one publisher of what crosses its ports (docs/architecture.md, "The tap"): the recorder, the live feed
  * and the FU-Remote relay each subscribe. JVM-local: a subscription is a queue in this process.
  */
trait GatewayTap {

  /** A new reader named `reader` (in the figures) with a queue of `capacity` entries. */
  def subscribe(reader: String, capacity: Int): TapSubscription

  /** Every current reader's figures. */
  def readers: Vector[TapReaderStats]
}
