package naogateway.wire

import java.io.ByteArrayOutputStream
import java.nio.ByteBuffer
import java.util.zip.GZIPOutputStream

import scala.util.control.NonFatal

import naogateway.proto.Message

/** The two header forms of an FU-Remote frame (docs/protocol.md §4). */
sealed abstract class HeaderForm(val headerBytes: Int) extends Product with Serializable

/** The header forms a reader accepts; `Legacy` is what the CM-530 firmware of the thesis sends. */
object HeaderForm {

  /** `00 2A flags 00`, `u32 type = 0`, `u32 length`: 12 bytes (the thesis, FUmanoids before 2014). */
  case object Legacy extends HeaderForm(12)

  /** `00 2A flags 00`, `u32 length`: 8 bytes (FUmanoids from 2014 on). */
  case object Compact extends HeaderForm(8)
}

/** What the header of a frame says. */
final case class FrameHeader(form: HeaderForm, gzip: Boolean, payloadLength: Int)

/** Why bytes are not a valid FU-Remote frame, or why a frame cannot be built. */
sealed trait FrameError extends Product with Serializable {

  /** A short text for logs and error replies. */
  def describe: String
}

/** Every way a frame can be refused, each a value, never an exception. */
object FrameError {

  /** Fewer bytes than the header needs. */
  final case class Truncated(needed: Int, got: Int) extends FrameError {
    def describe: String = s"truncated frame: needs $needed bytes, got $got"
  }

  /** The first two bytes are not operation 42, or the alignment byte is not 0. */
  final case class WrongOperation(operation: Int, alignment: Int) extends FrameError {
    def describe: String = s"not an FU-Remote frame: operation $operation, alignment byte $alignment"
  }

  /** Flag bits other than gzip (2) are set. */
  final case class UnsupportedFlags(flags: Int) extends FrameError {
    def describe: String = s"unsupported frame flags 0x${Integer.toHexString(flags)}"
  }

  /** The header's payload length disagrees with the bytes that follow it. */
  final case class LengthMismatch(declared: Long, actual: Int) extends FrameError {
    def describe: String = s"frame declares $declared payload bytes but carries $actual"
  }

  /** The payload is flagged gzip but does not inflate. */
  final case class BadGzip(reason: String) extends FrameError {
    def describe: String = s"bad gzip payload: $reason"
  }

  /** The (inflated) payload is not a protobuf `Message`. */
  final case class BadProtobuf(reason: String) extends FrameError {
    def describe: String = s"bad protobuf payload: $reason"
  }

  /** The datagram is larger than the robot's 1400-byte module buffer. */
  final case class Oversize(size: Int, limit: Int) extends FrameError {
    def describe: String = s"frame of $size bytes exceeds the $limit-byte datagram limit"
  }
}

/** A frame read from the wire: its header and the protobuf bytes (already inflated when gzip-flagged). */
final case class RawFrame(header: FrameHeader, protobuf: Array[Byte])

/** A frame read from the wire and parsed into a `Message`. */
final case class DecodedFrame(header: FrameHeader, message: Message)

/** Encoder and decoder of FUmanoids frames (docs/protocol.md §4): pure functions, decoding never throws. */
object FumanoidsFrame {

  /** Flag bit meaning "the payload is gzip-compressed". */
  val GzipFlag: Int = 2

  /** A gzip payload may inflate to at most this much, so a tiny datagram cannot exhaust memory. */
  val MaxInflatedBytes: Int = 64 * 1024

  private val MinHeaderBytes = HeaderForm.Compact.headerBytes

  /** Frames `message` for the wire; refuses anything over 1400 bytes. */
  def encode(
      message: Message,
      form: HeaderForm = HeaderForm.Legacy,
      gzip: Boolean = false
  ): Either[FrameError.Oversize, Array[Byte]] =
    encodeProtobuf(message.toByteArray, form, gzip)

  /** Frames already serialized protobuf bytes of a `Message`; refuses anything over 1400 bytes. */
  def encodeProtobuf(
      protobuf: Array[Byte],
      form: HeaderForm = HeaderForm.Legacy,
      gzip: Boolean = false
  ): Either[FrameError.Oversize, Array[Byte]] = {
    val payload = if (gzip) deflate(protobuf) else protobuf
    val size = form.headerBytes + payload.length
    if (size > WireLimits.MaxDatagramBytes) Left(FrameError.Oversize(size, WireLimits.MaxDatagramBytes))
    else {
      val buffer = ByteBuffer.allocate(size) // big-endian, as the header demands
      buffer.putShort(WireLimits.FumanoidsOperation.toShort)
      buffer.put((if (gzip) GzipFlag else 0).toByte)
      buffer.put(0.toByte)
      if (form == HeaderForm.Legacy) buffer.putInt(0)
      buffer.putInt(payload.length)
      buffer.put(payload)
      Right(buffer.array())
    }
  }

  /** Reads the header of a datagram; accepts both header forms. */
  def decodeHeader(bytes: Array[Byte]): Either[FrameError, FrameHeader] =
    if (bytes.length > WireLimits.MaxDatagramBytes) Left(FrameError.Oversize(bytes.length, WireLimits.MaxDatagramBytes))
    else if (bytes.length < MinHeaderBytes) Left(FrameError.Truncated(MinHeaderBytes, bytes.length))
    else {
      val operation = u16(bytes, 0)
      val flags = bytes(2) & 0xff
      val alignment = bytes(3) & 0xff
      if (operation != WireLimits.FumanoidsOperation || alignment != 0)
        Left(FrameError.WrongOperation(operation, alignment))
      else if ((flags & ~GzipFlag) != 0) Left(FrameError.UnsupportedFlags(flags))
      else {
        val word = u32(bytes, 4)
        // A Message is never empty (robotID is required), so a zero here can only be the legacy type field.
        val form = if (word != 0L) HeaderForm.Compact else HeaderForm.Legacy
        if (bytes.length < form.headerBytes) Left(FrameError.Truncated(form.headerBytes, bytes.length))
        else {
          val declared = if (form == HeaderForm.Compact) word else u32(bytes, 8)
          val actual = bytes.length - form.headerBytes
          if (declared != actual.toLong) Left(FrameError.LengthMismatch(declared, actual))
          else Right(FrameHeader(form, (flags & GzipFlag) != 0, actual))
        }
      }
    }

  /** Reads the header and returns the protobuf bytes, inflated when gzip-flagged. */
  def decodeRaw(bytes: Array[Byte]): Either[FrameError, RawFrame] =
    decodeHeader(bytes).flatMap { header =>
      val payload = java.util.Arrays.copyOfRange(bytes, header.form.headerBytes, bytes.length)
      if (header.gzip) inflate(payload).map(RawFrame(header, _))
      else Right(RawFrame(header, payload))
    }

  /** Decodes a whole frame into a `Message`; every input gives a value or a typed error. */
  def decode(bytes: Array[Byte]): Either[FrameError, DecodedFrame] =
    decodeRaw(bytes).flatMap { raw =>
      parseMessage(raw.protobuf).map(DecodedFrame(raw.header, _))
    }

  /** Parses protobuf bytes into a `Message` by the rules of docs/protocol.md §5, as a value or a typed error. */
  def parseMessage(protobuf: Array[Byte]): Either[FrameError.BadProtobuf, Message] =
    try {
      val (bytes, offset, length) = WireRules.normalize(protobuf, 0, protobuf.length)
      Right(Message.parseFrom(com.google.protobuf.CodedInputStream.newInstance(bytes, offset, length)))
    } catch { case NonFatal(e) => Left(FrameError.BadProtobuf(String.valueOf(e.getMessage))) }

  private def u16(b: Array[Byte], at: Int): Int = ((b(at) & 0xff) << 8) | (b(at + 1) & 0xff)

  private def u32(b: Array[Byte], at: Int): Long =
    ((b(at) & 0xffL) << 24) | ((b(at + 1) & 0xffL) << 16) | ((b(at + 2) & 0xffL) << 8) | (b(at + 3) & 0xffL)

  private def deflate(bytes: Array[Byte]): Array[Byte] = {
    val out = new ByteArrayOutputStream(bytes.length / 2 + 32)
    val gzip = new GZIPOutputStream(out)
    try gzip.write(bytes)
    finally gzip.close()
    out.toByteArray
  }

  /** Inflates exactly one gzip member (RFC 1952), as docs/protocol.md §4.3 demands: a second member or any byte after
    * the member's trailer is refused, so every receiver reads the same payload.
    */
  private def inflate(bytes: Array[Byte]): Either[FrameError.BadGzip, Array[Byte]] = {
    def bad(reason: String) = Left(FrameError.BadGzip(reason))
    def u8(at: Int): Int = bytes(at) & 0xff
    def le16(at: Int): Int = u8(at) | (u8(at + 1) << 8)
    def le32(at: Int): Long = (le16(at) | (le16(at + 2).toLong << 16)) & 0xffffffffL
    // Skips a zero-terminated field of the header; -1 when the terminator is missing.
    def afterZero(from: Int): Int = { val z = bytes.indexOf(0.toByte, from); if (z < 0) -1 else z + 1 }
    val FText = 1; val FHcrc = 2; val FExtra = 4; val FName = 8; val FComment = 16
    if (bytes.length < 18) bad(s"${bytes.length} bytes cannot hold a gzip member")
    else if (u8(0) != 0x1f || u8(1) != 0x8b) bad("not in gzip format")
    else if (u8(2) != 8) bad(s"compression method ${u8(2)} is not deflate")
    else if ((u8(3) & ~(FText | FHcrc | FExtra | FName | FComment)) != 0)
      bad(s"reserved gzip flags 0x${Integer.toHexString(u8(3))}")
    else {
      val flags = u8(3)
      var at = 10
      if ((flags & FExtra) != 0) at = if (at + 2 <= bytes.length) at + 2 + le16(at) else -1
      if (at >= 0 && (flags & FName) != 0) at = afterZero(at)
      if (at >= 0 && (flags & FComment) != 0) at = afterZero(at)
      if (at >= 0 && (flags & FHcrc) != 0) at += 2
      if (at < 0 || at > bytes.length - 8) bad("truncated gzip header")
      else {
        val inflater = new java.util.zip.Inflater(true)
        try {
          inflater.setInput(bytes, at, bytes.length - at)
          val out = new ByteArrayOutputStream(bytes.length * 4)
          val chunk = new Array[Byte](4096)
          var failure: Option[String] = None
          while (failure.isEmpty && !inflater.finished()) {
            val n = inflater.inflate(chunk)
            out.write(chunk, 0, n)
            if (out.size > MaxInflatedBytes) failure = Some(s"inflates beyond $MaxInflatedBytes bytes")
            else if (n == 0 && !inflater.finished())
              failure = Some("truncated deflate data") // no progress: input used up
          }
          failure match {
            case Some(reason) => bad(reason)
            case None =>
              val trailer = bytes.length - inflater.getRemaining
              val inflated = out.toByteArray
              val crc = new java.util.zip.CRC32()
              crc.update(inflated)
              if (inflater.getRemaining < 8) bad("truncated gzip trailer")
              else if (inflater.getRemaining > 8) bad(s"${inflater.getRemaining - 8} bytes after the gzip member")
              else if (le32(trailer) != crc.getValue) bad("CRC-32 mismatch")
              else if (le32(trailer + 4) != (inflated.length.toLong & 0xffffffffL)) bad("inflated size mismatch")
              else Right(inflated)
          }
        } catch { case NonFatal(e) => bad(String.valueOf(e.getMessage)) }
        finally inflater.end()
      }
    }
  }
}
