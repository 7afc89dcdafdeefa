package naogateway.wire

import scala.util.Try

import com.google.protobuf.{CodedOutputStream, WireFormat}

import naogateway.proto.{BodyProto, BusBridge, Message}

/** Frames carrying a `busBridge` (docs/protocol.md 6.9, extension 7107): the bus bridge's request from the gateway and
  * the robot's reply, each one FU-Remote frame in one secure-stream payload.
  */
object BusBridgeFrame {

  /** The extension number of `busBridge`. */
  val Field: Int = 7107

  /** The frame of robot `robotId` carrying `bridge`; `None` only when it would not fit a frame (it always does for the
    * 143-byte requests and 261-byte replies of 6.9).
    */
  def encode(robotId: Int, bridge: BusBridge, form: HeaderForm = HeaderForm.Legacy): Option[Array[Byte]] = {
    val size = bridge.serializedSize
    val bytes = new Array[Byte](CodedOutputStream.computeInt32Size(1, robotId) +
      CodedOutputStream.computeTagSize(Field) + CodedOutputStream.computeUInt32SizeNoTag(size) + size)
    val out = CodedOutputStream.newInstance(bytes)
    out.writeInt32(1, robotId)
    out.writeTag(Field, WireFormat.WIRETYPE_LENGTH_DELIMITED)
    out.writeUInt32NoTag(size)
    bridge.writeTo(out)
    out.checkNoSpaceLeft()
    FumanoidsFrame.encodeProtobuf(bytes, form).toOption
  }

  // The field's key bytes (7107 << 3 | 2 as a varint): a frame without them carries no busBridge.
  private val Key = Array(0x9a.toByte, 0xbc.toByte, 0x03.toByte)

  /** Whether `frame` may carry a `busBridge` (its key bytes occur): a cheap test before [[decode]]. */
  def mayCarry(frame: Array[Byte]): Boolean = frame.indexOfSlice(Key) >= 0 && Datagram.isFuRemoteFrame(frame)

  /** The robot id and `busBridge` of a frame, if it is a readable frame that carries one. */
  def decode(frame: Array[Byte]): Option[(Int, BusBridge)] =
    FumanoidsFrame.decodeRaw(frame).toOption.flatMap { raw =>
      Try(Message.parseFrom(raw.protobuf)).toOption.flatMap(m =>
        Try(m.extension(BodyProto.busBridge)).toOption.flatten.map(m.robotID -> _))
    }
}
