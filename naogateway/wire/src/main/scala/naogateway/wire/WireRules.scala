package naogateway.wire

import java.nio.charset.StandardCharsets

import com.google.protobuf.{ByteString, CodedInputStream, CodedOutputStream, InvalidProtocolBufferException, WireFormat}
import com.google.protobuf.descriptor.FieldDescriptorProto.Type
import scalapb.descriptors.{Descriptor, FieldDescriptor, ScalaType}

import naogateway.proto._

/** The decoding rules of docs/protocol.md §5 that ScalaPB alone does not follow, applied before it parses.
  *
  * ScalaPB refuses unknown groups, refuses a whole message for one string that is not UTF-8, and cuts a varint beyond
  * 32 bits to its low bits. The document says instead: unknown fields of every wire type are skipped (groups included),
  * a malformed string is read with U+FFFD for each bad sequence, and a 32-bit field whose varint does not fit is
  * refused, as nanopb (the firmware's decoder) does. Both general decode paths run `normalize` first, so they agree;
  * `KeepAliveReader` applies the same rules itself to the keep-alive's fields and leaves everything else here.
  */
private[wire] object WireRules {

  /** How deep sub-messages may nest; deeper input is refused rather than risking the stack. */
  private val MaxDepth = 32

  private val extensions: Map[Int, Descriptor] = Map(
    MessageContents.StatusField -> Status.scalaDescriptor,
    MessageContents.RobotHealthField -> RobotHealth.scalaDescriptor,
    MessageContents.ServoTelemetryField -> ServoTelemetry.scalaDescriptor,
    MessageContents.DebuggingCommandsField -> DebuggingCommands.scalaDescriptor,
    MessageContents.DebugDataField -> DebugData.scalaDescriptor,
    MessageContents.HavimoRegionsField -> HaViMoRegionFrame.scalaDescriptor,
    MessageContents.HavimoGridField -> HaViMoGridFrame.scalaDescriptor,
    MessageContents.RpcRequestField -> Request.scalaDescriptor,
    MessageContents.RpcResponseField -> Response.scalaDescriptor
  )

  /** What the rules need to know of one field: how its varint is bounded, whether it is text or a sub-message. */
  private sealed trait Kind
  private case object Other extends Kind
  private case object Int32 extends Kind
  private case object UInt32 extends Kind
  private case object SInt32 extends Kind
  private case object Text extends Kind
  private final case class Sub(descriptor: Descriptor) extends Kind

  private def kindOf(fd: FieldDescriptor): Kind = fd.scalaType match {
    case ScalaType.Message(d) => Sub(d)
    case _ => fd.protoType match {
        case Type.TYPE_INT32 | Type.TYPE_ENUM => Int32
        case Type.TYPE_UINT32                 => UInt32
        case Type.TYPE_SINT32                 => SInt32
        case Type.TYPE_STRING                 => Text
        case _                                => Other
      }
  }

  /** The fields of one message by number, read off its descriptor once (plus, for `Message`, its extensions). */
  private final class Schema(kinds: Map[Int, Kind]) {
    private val table: Array[Kind] = {
      val t = Array.fill[Kind](if (kinds.isEmpty) 1 else kinds.keys.max + 1)(Other)
      kinds.foreach { case (n, k) => t(n) = k }
      t
    }
    def kind(number: Int): Kind = if (number < table.length) table(number) else Other
  }

  // Every message reachable from `Message`, built once; recursive messages (MixedValue) share their entry.
  private val schemas: Map[Descriptor, Schema] = {
    def fields(d: Descriptor): Map[Int, Kind] = d.fields.iterator.map(f => f.number -> kindOf(f)).toMap
    @scala.annotation.tailrec
    def reach(todo: List[Descriptor], seen: Map[Descriptor, Schema]): Map[Descriptor, Schema] = todo match {
      case Nil                           => seen
      case d :: rest if seen.contains(d) => reach(rest, seen)
      case d :: rest =>
        val kinds = fields(d)
        reach(kinds.values.collect { case Sub(s) => s }.toList ++ rest, seen.updated(d, new Schema(kinds)))
    }
    reach(extensions.values.toList, Map.empty)
  }

  private val messageSchema =
    new Schema(Message.scalaDescriptor.fields.iterator.map(f => f.number -> kindOf(f)).toMap ++ extensions.map {
      case (n, d) => n -> Sub(d)
    })

  /** The bytes of a `Message` as ScalaPB may read them: the same slice when nothing needs rewriting, else a new array
    * without groups and with malformed strings repaired. Throws `InvalidProtocolBufferException` for a 32-bit field
    * whose varint does not fit, an end-group tag without its start, or malformed framing.
    */
  def normalize(bytes: Array[Byte], offset: Int, length: Int): (Array[Byte], Int, Int) =
    if (!needsRewrite(CodedInputStream.newInstance(bytes, offset, length), bytes, offset, messageSchema, 0))
      (bytes, offset, length)
    else {
      val out = rewrite(CodedInputStream.newInstance(bytes, offset, length), messageSchema)
      (out, 0, out.length)
    }

  /** Checks every field; true when a group or a malformed string must be rewritten. */
  private def needsRewrite(
      in: CodedInputStream, bytes: Array[Byte], offset: Int, schema: Schema, depth: Int): Boolean = {
    if (depth > MaxDepth) throw new InvalidProtocolBufferException("sub-messages nested too deeply")
    var rewrite = false
    var done = false
    while (!done) {
      val tag = in.readTag()
      if (tag == 0) done = true
      else {
        val number = WireFormat.getTagFieldNumber(tag)
        WireFormat.getTagWireType(tag) match {
          case WireFormat.WIRETYPE_VARINT =>
            checkRange(schema.kind(number), number, in.readRawVarint64())
          case WireFormat.WIRETYPE_LENGTH_DELIMITED =>
            schema.kind(number) match {
              case Sub(d) =>
                val limit = in.pushLimit(in.readRawVarint32())
                rewrite |= needsRewrite(in, bytes, offset, schemas(d), depth + 1)
                in.popLimit(limit)
              case Text =>
                // Checked in place: the stream reads `bytes` from `offset`, so no copy of the string is made.
                val size = in.readRawVarint32()
                if (size < 0 || size > in.getBytesUntilLimit)
                  throw new InvalidProtocolBufferException("truncated string")
                rewrite |= !utf8(bytes, offset + in.getTotalBytesRead, size)
                in.skipRawBytes(size)
              case _ => in.skipField(tag)
            }
          case WireFormat.WIRETYPE_START_GROUP => in.skipField(tag); rewrite = true
          case WireFormat.WIRETYPE_END_GROUP =>
            throw new InvalidProtocolBufferException(s"end of group $number that was never started")
          case _ => in.skipField(tag) // fixed 32 / 64 bits; an invalid wire type throws here
        }
      }
    }
    rewrite
  }

  /** Copies a message, dropping groups and replacing malformed strings by their U+FFFD reading. */
  private def rewrite(in: CodedInputStream, schema: Schema): Array[Byte] = {
    val buffer = new java.io.ByteArrayOutputStream()
    val out = CodedOutputStream.newInstance(buffer)
    var done = false
    while (!done) {
      val tag = in.readTag()
      if (tag == 0) done = true
      else {
        val number = WireFormat.getTagFieldNumber(tag)
        WireFormat.getTagWireType(tag) match {
          case WireFormat.WIRETYPE_START_GROUP => in.skipField(tag)
          case WireFormat.WIRETYPE_LENGTH_DELIMITED =>
            schema.kind(number) match {
              case Sub(d) =>
                val limit = in.pushLimit(in.readRawVarint32())
                val nested = rewrite(in, schemas(d))
                in.popLimit(limit)
                out.writeByteArray(number, nested)
              case Text =>
                val raw = in.readBytes()
                out.writeBytes(number, if (raw.isValidUtf8) raw else repaired(raw))
              case _ => out.writeBytes(number, in.readBytes())
            }
          case WireFormat.WIRETYPE_VARINT =>
            out.writeUInt32NoTag(tag); out.writeUInt64NoTag(in.readRawVarint64())
          case WireFormat.WIRETYPE_FIXED64 =>
            out.writeUInt32NoTag(tag); out.writeFixed64NoTag(in.readRawLittleEndian64())
          case WireFormat.WIRETYPE_FIXED32 =>
            out.writeUInt32NoTag(tag); out.writeFixed32NoTag(in.readRawLittleEndian32())
          case other => throw new InvalidProtocolBufferException(s"invalid wire type $other") // needsRewrite refused it
        }
      }
    }
    out.flush()
    buffer.toByteArray
  }

  /** Whether `size` bytes from `at` are valid UTF-8; ASCII, the usual case, without allocating. */
  private def utf8(bytes: Array[Byte], at: Int, size: Int): Boolean = {
    var i = at
    while (i < at + size && bytes(i) >= 0) i += 1
    i == at + size || {
      val decoder = StandardCharsets.UTF_8.newDecoder() // reports malformed input by default
      try { decoder.decode(java.nio.ByteBuffer.wrap(bytes, i, at + size - i)); true }
      catch { case _: java.nio.charset.CharacterCodingException => false }
    }
  }

  private def repaired(raw: ByteString): ByteString =
    ByteString.copyFromUtf8(new String(raw.toByteArray, StandardCharsets.UTF_8))

  /** Refuses a varint that does not fit the 32-bit type declared for its field (docs/protocol.md §5). */
  private def checkRange(kind: Kind, number: Int, value: Long): Unit = {
    val fits = kind match {
      case Int32  => value == value.toInt.toLong
      case UInt32 => (value >>> 32) == 0L
      case SInt32 => val decoded = (value >>> 1) ^ -(value & 1); decoded == decoded.toInt.toLong
      case _      => true
    }
    if (!fits)
      throw new InvalidProtocolBufferException(
        s"varint ${java.lang.Long.toUnsignedString(value)} does not fit the 32-bit field $number"
      )
  }
}
