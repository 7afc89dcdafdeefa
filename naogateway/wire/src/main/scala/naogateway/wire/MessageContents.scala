package naogateway.wire

import scala.util.control.NonFatal

import com.google.protobuf.{CodedInputStream, CodedOutputStream, WireFormat}

import naogateway.proto._

/** The known extensions of one `Message`, read once and checked, so no caller meets a lazily failing parse. */
final case class MessageContents(
    robotId: Int,
    status: Option[Status] = None,
    robotHealth: Option[RobotHealth] = None,
    debuggingCommands: Option[DebuggingCommands] = None,
    debugData: Option[DebugData] = None,
    havimoRegions: Option[HaViMoRegionFrame] = None,
    havimoGrid: Option[HaViMoGridFrame] = None,
    rpcRequest: Option[Request] = None,
    rpcResponse: Option[Response] = None,
    servoTelemetry: Option[ServoTelemetry] = None,
    unknownExtensions: Vector[Int] = Vector.empty
) {

  /** The protobuf bytes of `toMessage`, written in one pass (robotID, then extensions by ascending number). */
  def toProtobuf: Array[Byte] = {
    val parts = Array[(Int, Option[scalapb.GeneratedMessage])](
      MessageContents.StatusField -> status,
      MessageContents.DebuggingCommandsField -> debuggingCommands,
      MessageContents.DebugDataField -> debugData,
      MessageContents.HavimoRegionsField -> havimoRegions,
      MessageContents.HavimoGridField -> havimoGrid,
      MessageContents.RobotHealthField -> robotHealth,
      MessageContents.ServoTelemetryField -> servoTelemetry,
      MessageContents.RpcRequestField -> rpcRequest,
      MessageContents.RpcResponseField -> rpcResponse
    )
    var size = CodedOutputStream.computeInt32Size(1, robotId)
    parts.foreach { case (field, part) =>
      part.foreach { m =>
        val n = m.serializedSize
        size += CodedOutputStream.computeTagSize(field) + CodedOutputStream.computeUInt32SizeNoTag(n) + n
      }
    }
    val bytes = new Array[Byte](size)
    val out = CodedOutputStream.newInstance(bytes)
    out.writeInt32(1, robotId)
    parts.foreach { case (field, part) =>
      part.foreach { m =>
        out.writeTag(field, WireFormat.WIRETYPE_LENGTH_DELIMITED)
        out.writeUInt32NoTag(m.serializedSize)
        m.writeTo(out)
      }
    }
    out.checkNoSpaceLeft()
    bytes
  }

  /** The `Message` carrying exactly these contents (unknown extensions are not carried over). */
  def toMessage: Message = {
    var message = Message(robotID = robotId)
    status.foreach(s => message = message.withExtension(MessageProto.status)(Some(s)))
    robotHealth.foreach(h => message = message.withExtension(MessageProto.robotHealth)(Some(h)))
    debuggingCommands.foreach(c => message = message.withExtension(DebuggingProto.debuggingCommands)(Some(c)))
    debugData.foreach(d => message = message.withExtension(DebuggingProto.debugData)(Some(d)))
    havimoRegions.foreach(r => message = message.withExtension(HavimoProto.havimoRegions)(Some(r)))
    havimoGrid.foreach(g => message = message.withExtension(HavimoProto.havimoGrid)(Some(g)))
    rpcRequest.foreach(r => message = message.withExtension(RpcProto.rpcRequest)(Some(r)))
    rpcResponse.foreach(r => message = message.withExtension(RpcProto.rpcResponse)(Some(r)))
    servoTelemetry.foreach(t => message = message.withExtension(BodyProto.servoTelemetry)(Some(t)))
    message
  }
}

/** Reading and writing the extensions this project knows; see docs/protocol.md for their numbers. */
object MessageContents {

  /** Extension numbers of FU-Remote's own messages that this project uses. */
  val StatusField: Int = 23

  /** The first and last extension number reserved for this project's own messages. */
  val ProjectRange: Range.Inclusive = 7100 to 7199

  val DebuggingCommandsField: Int = 7101
  val DebugDataField: Int = 7102
  val HavimoRegionsField: Int = 7103
  val HavimoGridField: Int = 7104
  val RobotHealthField: Int = 7105

  /** Servo telemetry in the keep-alive (docs/protocol.md 6.8). */
  val ServoTelemetryField: Int = 7106
  val RpcRequestField: Int = 7110
  val RpcResponseField: Int = 7111

  private val known =
    Set(
      StatusField,
      RobotHealthField,
      DebuggingCommandsField,
      DebugDataField,
      HavimoRegionsField,
      HavimoGridField,
      RpcRequestField,
      RpcResponseField,
      ServoTelemetryField
    )

  /** Parses every known extension of `message`; a malformed one is a typed error, unknown ones are listed. */
  def of(message: Message): Either[FrameError.BadProtobuf, MessageContents] =
    try
      Right(
        MessageContents(
          robotId = message.robotID,
          status = message.extension(MessageProto.status),
          robotHealth = message.extension(MessageProto.robotHealth),
          debuggingCommands = message.extension(DebuggingProto.debuggingCommands),
          debugData = message.extension(DebuggingProto.debugData),
          havimoRegions = message.extension(HavimoProto.havimoRegions),
          havimoGrid = message.extension(HavimoProto.havimoGrid),
          rpcRequest = message.extension(RpcProto.rpcRequest),
          rpcResponse = message.extension(RpcProto.rpcResponse),
          servoTelemetry = message.extension(BodyProto.servoTelemetry),
          unknownExtensions = message.unknownFields.asMap.keys.filterNot(known).toVector.sorted
        )
      )
    catch { case NonFatal(e) => Left(FrameError.BadProtobuf(s"extension: ${e.getMessage}")) }

  /** Decodes a datagram all the way to its contents. */
  def decodeFrame(bytes: Array[Byte]): Either[FrameError, (FrameHeader, MessageContents)] =
    FumanoidsFrame.decodeHeader(bytes) match {
      case Right(header) if !header.gzip =>
        val offset = header.form.headerBytes
        KeepAliveReader.read(bytes, offset, header.payloadLength) match {
          case null     => general(bytes, offset, header.payloadLength).map(header -> _)
          case contents => Right(header -> contents)
        }
      case Right(header) => FumanoidsFrame.decodeRaw(bytes).flatMap(raw => parse(raw.protobuf).map(header -> _))
      case Left(error)   => Left(error)
    }

  /** Parses the protobuf bytes of a `Message` in one pass, reading known extensions in place. */
  def parse(bytes: Array[Byte]): Either[FrameError.BadProtobuf, MessageContents] = parse(bytes, 0, bytes.length)

  /** Parses `length` protobuf bytes from `offset`; same result as `of(Message.parseFrom(...))`, without the detour. */
  def parse(bytes: Array[Byte], offset: Int, length: Int): Either[FrameError.BadProtobuf, MessageContents] =
    KeepAliveReader.read(bytes, offset, length) match {
      case null     => general(bytes, offset, length)
      case contents => Right(contents)
    }

  /** Any `Message`: the rules of docs/protocol.md §5 applied by `WireRules.normalize`, then one decoding pass. */
  private[wire] def general(
      bytes: Array[Byte], offset: Int, length: Int): Either[FrameError.BadProtobuf, MessageContents] =
    try {
      val (normalized, from, size) = WireRules.normalize(bytes, offset, length)
      fastParse(normalized, from, size)
    } catch { case NonFatal(e) => Left(FrameError.BadProtobuf(String.valueOf(e.getMessage))) }

  /** The one-pass reading of bytes that `WireRules.normalize` has already checked (no groups, strings repaired). */
  private def fastParse(bytes: Array[Byte], offset: Int, length: Int): Either[FrameError.BadProtobuf, MessageContents] =
    try {
      val in = CodedInputStream.newInstance(bytes, offset, length)
      var robotId = 0
      var seenRobotId = false
      var c = MessageContents(0)
      var unknown = Vector.empty[Int]
      var repeated = false
      var done = false
      while (!done) {
        val tag = in.readTag()
        val field = WireFormat.getTagFieldNumber(tag)
        val wireType = WireFormat.getTagWireType(tag)
        if (tag == 0) done = true
        else if (field == 1 && wireType == WireFormat.WIRETYPE_VARINT) {
          robotId = in.readInt32(); seenRobotId = true
        } else if (wireType == WireFormat.WIRETYPE_LENGTH_DELIMITED && known(field)) {
          field match {
            case StatusField => repeated ||= c.status.isDefined; c = c.copy(status = Some(nested(in, Status)))
            case RobotHealthField =>
              repeated ||= c.robotHealth.isDefined; c = c.copy(robotHealth = Some(nested(in, RobotHealth)))
            case DebuggingCommandsField =>
              repeated ||= c.debuggingCommands.isDefined
              c = c.copy(debuggingCommands = Some(nested(in, DebuggingCommands)))
            case DebugDataField =>
              repeated ||= c.debugData.isDefined; c = c.copy(debugData = Some(nested(in, DebugData)))
            case HavimoRegionsField =>
              repeated ||= c.havimoRegions.isDefined; c = c.copy(havimoRegions = Some(nested(in, HaViMoRegionFrame)))
            case HavimoGridField =>
              repeated ||= c.havimoGrid.isDefined; c = c.copy(havimoGrid = Some(nested(in, HaViMoGridFrame)))
            case RpcRequestField =>
              repeated ||= c.rpcRequest.isDefined; c = c.copy(rpcRequest = Some(nested(in, Request)))
            case ServoTelemetryField =>
              repeated ||= c.servoTelemetry.isDefined; c = c.copy(servoTelemetry = Some(nested(in, ServoTelemetry)))
            case _ => repeated ||= c.rpcResponse.isDefined; c = c.copy(rpcResponse = Some(nested(in, Response)))
          }
        } else {
          if (!unknown.contains(field)) unknown = unknown :+ field
          in.skipField(tag)
        }
      }
      // Protobuf merges a message field that occurs twice; rare enough to take the general path for it.
      if (repeated) slowParse(bytes, offset, length)
      else if (!seenRobotId) Left(FrameError.BadProtobuf("Message is missing the required robotID"))
      else Right(c.copy(robotId = robotId, unknownExtensions = unknown.sorted))
    } catch { case NonFatal(e) => Left(FrameError.BadProtobuf(String.valueOf(e.getMessage))) }

  private def slowParse(bytes: Array[Byte], offset: Int, length: Int): Either[FrameError.BadProtobuf, MessageContents] =
    try of(Message.parseFrom(CodedInputStream.newInstance(bytes, offset, length))) // already normalized
    catch { case NonFatal(e) => Left(FrameError.BadProtobuf(String.valueOf(e.getMessage))) }

  private def nested[A <: scalapb.GeneratedMessage](in: CodedInputStream,
      companion: scalapb.GeneratedMessageCompanion[A]): A = {
    val limit = in.pushLimit(in.readRawVarint32())
    val message = companion.parseFrom(in)
    in.popLimit(limit)
    message
  }

  /** Encodes contents as a frame for the wire. */
  def encodeFrame(
      contents: MessageContents,
      form: HeaderForm = HeaderForm.Legacy,
      gzip: Boolean = false
  ): Either[FrameError.Oversize, Array[Byte]] =
    FumanoidsFrame.encodeProtobuf(contents.toProtobuf, form, gzip)
}
