package naogateway.gateway.recording

import java.net.InetSocketAddress

import com.google.protobuf.CodedOutputStream

import naogateway.api.recording.Decision
import naogateway.proto.{RecordedDirection, RecordedPort}

/** Protobuf bytes of the messages the writer thread writes, in one array reused from message to message (grown when
  * needed): the same bytes as the generated code's `toByteArray`, without an array, a `ByteString` and strings each.
  */
private[recording] final class Encoder {
  private var buffer = new Array[Byte](1024)

  /** The bytes of the last message encoded, from index 0. */
  def bytes: Array[Byte] = buffer

  private def room(size: Int): CodedOutputStream = {
    if (size > buffer.length) buffer = new Array[Byte](math.max(size, buffer.length * 2))
    CodedOutputStream.newInstance(buffer, 0, size)
  }

  /** `d` as a `RecordedDatagram` with `source` and `destination` (their address text in UTF-8), fields by number, the
    * optional robot id only when known; answers the length.
    */
  def datagram(d: DatagramEntry, source: Array[Byte], destination: Array[Byte]): Int = {
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

/** One queued entry; `nanoTime` is `System.nanoTime` when it was handed over. */
private[recording] sealed trait Entry { def nanoTime: Long }
private[recording] final case class DatagramEntry(nanoTime: Long, port: RecordedPort, received: Boolean,
    source: InetSocketAddress,
    destination: InetSocketAddress, bytes: Array[Byte], robotId: Int) extends Entry
private[recording] final case class DecisionEntry(nanoTime: Long, decision: Decision) extends Entry
