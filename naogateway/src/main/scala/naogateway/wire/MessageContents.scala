package naogateway.wire

import scala.util.control.NonFatal

import naogateway.proto._

/** The known extensions of one `Message`, read once and checked, so no caller meets a lazily failing parse. */
final case class MessageContents(
    robotId: Int,
    status: Option[Status] = None,
    debuggingCommands: Option[DebuggingCommands] = None,
    debugData: Option[DebugData] = None,
    havimoRegions: Option[HaViMoRegionFrame] = None,
    havimoGrid: Option[HaViMoGridFrame] = None,
    rpcRequest: Option[Request] = None,
    rpcResponse: Option[Response] = None,
    unknownExtensions: Vector[Int] = Vector.empty
) {

  /** The `Message` carrying exactly these contents (unknown extensions are not carried over). */
  def toMessage: Message = {
    var message = Message(robotID = robotId)
    status.foreach(s => message = message.withExtension(MessageProto.status)(Some(s)))
    debuggingCommands.foreach(c => message = message.withExtension(DebuggingProto.debuggingCommands)(Some(c)))
    debugData.foreach(d => message = message.withExtension(DebuggingProto.debugData)(Some(d)))
    havimoRegions.foreach(r => message = message.withExtension(HavimoProto.havimoRegions)(Some(r)))
    havimoGrid.foreach(g => message = message.withExtension(HavimoProto.havimoGrid)(Some(g)))
    rpcRequest.foreach(r => message = message.withExtension(RpcProto.rpcRequest)(Some(r)))
    rpcResponse.foreach(r => message = message.withExtension(RpcProto.rpcResponse)(Some(r)))
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
  val RpcRequestField: Int = 7110
  val RpcResponseField: Int = 7111

  private val known =
    Set(StatusField, DebuggingCommandsField, DebugDataField, HavimoRegionsField, HavimoGridField, RpcRequestField,
      RpcResponseField)

  /** Parses every known extension of `message`; a malformed one is a typed error, unknown ones are listed. */
  def of(message: Message): Either[FrameError.BadProtobuf, MessageContents] =
    try
      Right(
        MessageContents(
          robotId = message.robotID,
          status = message.extension(MessageProto.status),
          debuggingCommands = message.extension(DebuggingProto.debuggingCommands),
          debugData = message.extension(DebuggingProto.debugData),
          havimoRegions = message.extension(HavimoProto.havimoRegions),
          havimoGrid = message.extension(HavimoProto.havimoGrid),
          rpcRequest = message.extension(RpcProto.rpcRequest),
          rpcResponse = message.extension(RpcProto.rpcResponse),
          unknownExtensions = message.unknownFields.asMap.keys.filterNot(known).toVector.sorted
        )
      )
    catch { case NonFatal(e) => Left(FrameError.BadProtobuf(s"extension: ${e.getMessage}")) }

  /** Decodes a datagram all the way to its contents. */
  def decodeFrame(bytes: Array[Byte]): Either[FrameError, (FrameHeader, MessageContents)] =
    FumanoidsFrame.decode(bytes).flatMap(frame => of(frame.message).map(frame.header -> _))

  /** Encodes contents as a frame for the wire. */
  def encodeFrame(
      contents: MessageContents,
      form: HeaderForm = HeaderForm.Legacy,
      gzip: Boolean = false
  ): Either[FrameError.Oversize, Array[Byte]] =
    FumanoidsFrame.encode(contents.toMessage, form, gzip)
}
