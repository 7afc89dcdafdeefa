package naogateway.api.recording

import java.net.InetSocketAddress

import com.google.protobuf.CodedOutputStream

import naogateway.proto.RecordedDirection
import naogateway.wire.MessageContents

/** Protobuf bytes of the messages of a recording's channels, in one array reused from message to message (grown when
  * needed): the same bytes as the generated code's `toByteArray`, without an array, a `ByteString` and strings each.
  * The recorder's writer thread and the live feed each hold one; one thread uses it at a time.
  */
final class RecordEncoder {
  private var buffer = new Array[Byte](1024)

  /** The bytes of the last message encoded, from index 0. */
  def bytes: Array[Byte] = buffer

  private def room(size: Int): CodedOutputStream = {
    if (size > buffer.length) buffer = new Array[Byte](math.max(size, buffer.length * 2))
    CodedOutputStream.newInstance(buffer, 0, size)
  }

  /** `d` as a `RecordedDatagram` with `source` and `destination` (their address text in UTF-8,
    * [[RecordEncoder.addressBytes]]), fields by number, the optional robot id only when known; answers the length.
    */
  def datagram(d: Tapped.Datagram, source: Array[Byte], destination: Array[Byte]): Int = {
    val direction = if (d.received) RecordedDirection.RECEIVED.value else RecordedDirection.SENT.value
    val size = CodedOutputStream.computeEnumSize(1, d.port.value) + CodedOutputStream.computeEnumSize(2, direction) +
      CodedOutputStream.computeByteArraySize(3, source) + CodedOutputStream.computeByteArraySize(4, destination) +
      CodedOutputStream.computeByteArraySize(5, d.bytes) + (if (d.robotId >= 0)
                                                              CodedOutputStream.computeInt32Size(6, d.robotId)
                                                            else 0)
    val out = room(size)
    out.writeEnum(1, d.port.value)
    out.writeEnum(2, direction)
    out.writeByteArray(3, source)
    out.writeByteArray(4, destination)
    out.writeByteArray(5, d.bytes)
    if (d.robotId >= 0) out.writeInt32(6, d.robotId)
    out.checkNoSpaceLeft()
    size
  }

  /** `m`'s bytes; answers the length. */
  def message(m: scalapb.GeneratedMessage): Int = {
    val size = m.serializedSize
    val out = room(size)
    m.writeTo(out)
    out.checkNoSpaceLeft()
    size
  }
}

/** What goes on which channel: shared by the recorder and the live feed, so both carry the same. */
object RecordEncoder {

  private val NoAddress = new Array[Byte](0)

  /** An address as a `RecordedDatagram` holds it: its text ([[DecisionJson.address]]) in UTF-8; none when null. */
  def addressBytes(a: InetSocketAddress): Array[Byte] =
    if (a == null) NoAddress else DecisionJson.address(a).getBytes(java.nio.charset.StandardCharsets.UTF_8)

  /** Whether a robot's message goes on its `/robot/<id>/message` channel, whole: anything beyond a keep-alive's status,
    * health and servo telemetry (which have channels of their own).
    */
  def onMessageChannel(c: MessageContents): Boolean =
    c.debuggingCommands.isDefined || c.debugData.isDefined || c.havimoRegions.isDefined || c.havimoGrid.isDefined ||
      c.rpcRequest.isDefined || c.rpcResponse.isDefined || c.unknownExtensions.nonEmpty
}
