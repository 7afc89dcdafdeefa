package naogateway.wire

import java.nio.charset.StandardCharsets
import java.security.MessageDigest

import javax.crypto.Mac
import javax.crypto.spec.SecretKeySpec

import scala.util.control.NonFatal

import com.google.protobuf.{CodedInputStream, CodedOutputStream, WireFormat}

/** HKDF with HMAC-SHA256 (RFC 5869), on the JDK's own HMAC: how a robot's key comes from its team's key. */
object Hkdf {

  /** Bytes of one SHA-256 output, the most one expand step gives. */
  val HashBytes: Int = 32

  private def hmac(key: Array[Byte]): Mac = {
    val mac = Mac.getInstance("HmacSHA256")
    // An empty salt is HashLen zero bytes (RFC 5869 2.2); SecretKeySpec refuses an empty key.
    mac.init(new SecretKeySpec(if (key.isEmpty) new Array[Byte](HashBytes) else key, "HmacSHA256"))
    mac
  }

  /** HKDF-Extract: the pseudorandom key of `ikm` under `salt`. */
  def extract(salt: Array[Byte], ikm: Array[Byte]): Array[Byte] = hmac(salt).doFinal(ikm)

  /** HKDF-Expand: `length` bytes (at most 255 blocks) of output keying material from `prk` and `info`. */
  def expand(prk: Array[Byte], info: Array[Byte], length: Int): Array[Byte] = {
    require(length >= 0 && length <= 255 * HashBytes, s"HKDF gives at most ${255 * HashBytes} bytes")
    val mac = hmac(prk)
    val out = new Array[Byte](length)
    var block = Array.emptyByteArray
    var done = 0
    var counter = 1
    while (done < length) {
      mac.update(block)
      mac.update(info)
      mac.update(counter.toByte)
      block = mac.doFinal()
      val n = math.min(block.length, length - done)
      System.arraycopy(block, 0, out, done, n)
      done += n
      counter += 1
    }
    out
  }

  /** Extract then expand: `length` bytes of keying material. */
  def apply(salt: Array[Byte], ikm: Array[Byte], info: Array[Byte], length: Int): Array[Byte] =
    expand(extract(salt, ikm), info, length)
}

/** A team's key for signed frames (docs/protocol.md 6.7): the gateway's only secret, from which every robot's key is
  * derived. It never appears in `toString`, so never in a log, and nothing prints it.
  */
final class SigningKey private (private val secret: Array[Byte]) {

  /** Robot `robotId`'s key: HKDF-SHA256(salt "naogateway robot key", this key, "FUSIG2" | id as 4 bytes big-endian). */
  def robotKey(robotId: Int): RobotKey = {
    val info = java.nio.ByteBuffer.allocate(FrameSigning.Domain.length + 4).put(FrameSigning.Domain).putInt(robotId)
    new RobotKey(robotId, Hkdf(SigningKey.RobotKeySalt, secret, info.array(), RobotKey.Bytes))
  }

  override def toString: String = "SigningKey(<secret>)"
  override def equals(other: Any): Boolean = other match {
    case k: SigningKey => MessageDigest.isEqual(secret, k.secret)
    case _             => false
  }
  override def hashCode(): Int = 0
}

/** Reading a team key from config or the environment: fails closed, never turning signing off. */
object SigningKey {

  /** The shortest key accepted: 128 bits. */
  val MinBytes: Int = 16

  /** The longest key accepted: one SHA-256 block, as the firmware's HMAC takes it without hashing it first. */
  val MaxBytes: Int = 64

  /** HKDF's salt for robot keys: the 20 ASCII bytes of "naogateway robot key". */
  val RobotKeySalt: Array[Byte] = "naogateway robot key".getBytes(StandardCharsets.US_ASCII)

  /** A key from raw bytes, refused when shorter than [[MinBytes]] or longer than [[MaxBytes]]. */
  def fromBytes(bytes: Array[Byte]): Either[String, SigningKey] =
    if (bytes.length < MinBytes) Left(s"a signing key needs at least $MinBytes bytes, this one has ${bytes.length}")
    else if (bytes.length > MaxBytes) Left(s"a signing key has at most $MaxBytes bytes, this one has ${bytes.length}")
    else Right(new SigningKey(bytes.clone()))

  /** A key written as hexadecimal digits (32 to 128 of them); the error names the length only, never the digits. */
  def fromHex(hex: String): Either[String, SigningKey] = Hex.decode(hex).flatMap(fromBytes)
}

/** Hexadecimal key text, shared by team and robot keys. */
private[wire] object Hex {

  /** The bytes of `hex` (surrounding blanks ignored), or why not, without repeating any digit. */
  def decode(hex: String): Either[String, Array[Byte]] = {
    val digits = hex.trim
    if (digits.length % 2 != 0 || !digits.forall(c => Character.digit(c, 16) >= 0))
      Left(s"a signing key is an even number of hexadecimal digits (got ${digits.length} characters)")
    else Right(digits.grouped(2).map(Integer.parseInt(_, 16).toByte).toArray)
  }
}

/** One robot's key (docs/protocol.md 6.7): what the robot is built or flashed with, and what the gateway derives from
  * the team key to sign and check that robot's frames. Opens no other robot. Never in `toString`.
  */
final class RobotKey private[wire] (val robotId: Int, private val secret: Array[Byte]) {

  /** A fresh HMAC-SHA256 instance keyed with this key (instances are not thread-safe, so one per use). */
  private[wire] def hmac(): Mac = {
    val mac = Mac.getInstance("HmacSHA256")
    mac.init(new SecretKeySpec(secret, "HmacSHA256"))
    mac
  }

  /** The key as 64 lowercase hexadecimal digits: only for `robotctl keys`, which a team runs to build a robot. */
  def toHex: String = secret.map(b => f"${b & 0xff}%02x").mkString

  override def toString: String = s"RobotKey($robotId, <secret>)"
  override def equals(other: Any): Boolean = other match {
    case k: RobotKey => k.robotId == robotId && MessageDigest.isEqual(secret, k.secret)
    case _           => false
  }
  override def hashCode(): Int = robotId
}

/** Robot keys. */
object RobotKey {

  /** Bytes of a robot key (HKDF's L). */
  val Bytes: Int = 32

  /** Robot `robotId`'s key written as 64 hexadecimal digits (as `robotctl keys` prints it). */
  def fromHex(robotId: Int, hex: String): Either[String, RobotKey] =
    Hex.decode(hex).flatMap { b =>
      if (b.length == Bytes) Right(new RobotKey(robotId, b)) else Left(s"a robot key has $Bytes bytes, not ${b.length}")
    }
}

/** Who signed a frame: part of the MAC, so a robot's frame cannot be reflected back to it as the gateway's. */
sealed abstract class SignDirection(val code: Byte) extends Product with Serializable

/** The two directions of a signed link. */
object SignDirection {

  /** Frames a robot sends (keep-alives, replies, option lists, debug data, camera frames). */
  case object RobotToGateway extends SignDirection(1)

  /** Frames the gateway sends (requests, option commands). */
  case object GatewayToRobot extends SignDirection(2)
}

/** The link a signature belongs to, all of which the MAC covers besides the bytes: the direction, the robot (which
  * sends or is addressed) and its boot epoch.
  */
sealed trait SignedLink extends Product with Serializable {

  /** Which way the frame goes. */
  def direction: SignDirection

  /** The robot that sends the frame or that it is addressed to. */
  def robotId: Int

  /** The boot epoch in the MAC of a frame with `timestamp`. */
  def epochOf(timestamp: Long): Int
}

/** The two kinds of link. */
object SignedLink {

  /** Frames of robot `robotId`: the epoch is the timestamp's high 32 bits. */
  final case class FromRobot(robotId: Int) extends SignedLink {
    def direction: SignDirection = SignDirection.RobotToGateway
    def epochOf(timestamp: Long): Int = (timestamp >>> 32).toInt
  }

  /** Frames to robot `robotId` in its boot epoch `epoch` (the high 32 bits of its last accepted timestamp). */
  final case class ToRobot(robotId: Int, epoch: Int) extends SignedLink {
    def direction: SignDirection = SignDirection.GatewayToRobot
    def epochOf(timestamp: Long): Int = epoch
  }
}

/** Why a frame's signature was not accepted: a closed set, so counts per kind stay bounded. */
sealed abstract class SignatureError(val kind: String) extends Product with Serializable

/** The kinds of signature failure. */
object SignatureError {

  /** The frame carries no signature field. */
  case object Missing extends SignatureError("unsigned")

  /** A field follows the signature: those bytes would not be covered by the MAC. */
  case object NotLast extends SignatureError("signature not last")

  /** The signature field is not a well-formed `FrameSignature`. */
  case object Malformed extends SignatureError("malformed signature")

  /** The MAC does not match: another key, or altered bytes. */
  case object BadMac extends SignatureError("bad signature")

  /** The timestamp is not above the last accepted one: a replayed or reordered frame. */
  case object Replayed extends SignatureError("replayed")

  /** Every kind. */
  val all: Vector[SignatureError] = Vector(Missing, NotLast, Malformed, BadMac, Replayed)
}

/** A frame whose MAC matched: its timestamp, and how many leading bytes of the protobuf body were signed. */
final case class SignedBody(timestamp: Long, signedLength: Int)

/** The replay rule: a sender's timestamps only ever grow (compared as unsigned 64-bit numbers). */
final case class ReplayWindow(last: Option[Long]) {

  /** The window after accepting `timestamp`, or `Replayed` when it is not above the last accepted one. */
  def accept(timestamp: Long): Either[SignatureError, ReplayWindow] =
    if (last.exists(l => java.lang.Long.compareUnsigned(timestamp, l) <= 0)) Left(SignatureError.Replayed)
    else Right(ReplayWindow(Some(timestamp)))
}

/** The empty window. */
object ReplayWindow {

  /** Nothing accepted yet: any timestamp goes. */
  val empty: ReplayWindow = ReplayWindow(None)
}

/** Signed FU-Remote frames, "FUSIG2" (docs/protocol.md 6.7): a `FrameSignature` extension (number 7199, always the last
  * field of the `Message`) carrying a timestamp and the first 8 bytes of HMAC-SHA256(robot key, "FUSIG2" | direction
  * (1) | robot id (4) | boot epoch (4) | timestamp (8), all big-endian | the Message's bytes before the field). Peers
  * that do not sign (FU-Remote) skip the extension like any unknown one.
  */
object FrameSigning {

  /** The signature's extension number: the last of the project's range, so protobuf libraries write it last. */
  val Field: Int = 7199

  /** Bytes of the truncated MAC (64 bits, as much as MAVLink 2's 48 and then some). */
  val MacBytes: Int = 8

  /** The domain separator at the start of every MAC input and of every robot key's HKDF info. */
  val Domain: Array[Byte] = "FUSIG2".getBytes(StandardCharsets.US_ASCII)

  /** The encoded length of the signature field: tag (3) + length (1) + fixed64 (1 + 8) + mac (1 + 1 + 8). */
  val FieldBytes: Int = 23

  /** The bytes the MAC covers before the signed bytes: domain, direction, robot id, epoch, timestamp. */
  def macPrefix(link: SignedLink, timestamp: Long): Array[Byte] =
    java.nio.ByteBuffer.allocate(Domain.length + 1 + 4 + 4 + 8).put(Domain).put(link.direction.code)
      .putInt(link.robotId).putInt(link.epochOf(timestamp)).putLong(timestamp).array()

  /** The truncated MAC of `length` body bytes from `offset`. */
  def mac(
      key: RobotKey, link: SignedLink, timestamp: Long, body: Array[Byte], offset: Int, length: Int): Array[Byte] = {
    val hmac = key.hmac()
    hmac.update(macPrefix(link, timestamp))
    hmac.update(body, offset, length)
    java.util.Arrays.copyOf(hmac.doFinal(), MacBytes)
  }

  /** `body` (the protobuf bytes of a `Message`) with the signature field appended. */
  def sign(body: Array[Byte], key: RobotKey, link: SignedLink, timestamp: Long): Array[Byte] = {
    val tag = mac(key, link, timestamp, body, 0, body.length)
    val out = new Array[Byte](body.length + FieldBytes)
    System.arraycopy(body, 0, out, 0, body.length)
    val coded = CodedOutputStream.newInstance(out, body.length, FieldBytes)
    coded.writeTag(Field, WireFormat.WIRETYPE_LENGTH_DELIMITED)
    coded.writeUInt32NoTag(FieldBytes - 4)
    coded.writeFixed64(1, timestamp)
    coded.writeByteArray(2, tag)
    coded.checkNoSpaceLeft()
    out
  }

  /** `contents` as a signed frame in header form `form` (signed frames are never gzip-flagged: the MAC is the check).
    */
  def signFrame(contents: MessageContents, form: HeaderForm, key: RobotKey, link: SignedLink, timestamp: Long)
      : Either[FrameError.Oversize, Array[Byte]] =
    FumanoidsFrame.encodeProtobuf(sign(contents.toProtobuf, key, link, timestamp), form, gzip = false)

  /** An encoded, unsigned frame (either header form, never gzip-flagged) signed as it stands: the same header form, the
    * length grown by [[FieldBytes]], the signature field appended. For senders that encode first and sign at the moment
    * of sending, so timestamps follow the order frames leave in.
    */
  def signEncoded(
      frame: Array[Byte], key: RobotKey, link: SignedLink, timestamp: Long): Either[FrameError, Array[Byte]] =
    FumanoidsFrame.decodeHeader(frame).flatMap { header =>
      if (header.gzip) Left(FrameError.UnsupportedFlags(FumanoidsFrame.GzipFlag))
      else {
        val body = java.util.Arrays.copyOfRange(frame, header.form.headerBytes, frame.length)
        FumanoidsFrame.encodeProtobuf(sign(body, key, link, timestamp), header.form, gzip = false)
      }
    }

  /** Checks the signature of a whole received frame whose header decoded as `header` (a gzip-flagged payload is checked
    * after inflating; a frame that does not decode at all is `Malformed`). The replay rule is the caller's.
    */
  def verifyFrame(
      frame: Array[Byte], header: FrameHeader, key: RobotKey, link: SignedLink): Either[SignatureError, SignedBody] =
    if (!header.gzip) verify(frame, header.form.headerBytes, header.payloadLength, key, link)
    else
      FumanoidsFrame.decodeRaw(frame) match {
        case Right(raw) => verify(raw.protobuf, 0, raw.protobuf.length, key, link)
        case Left(_)    => Left(SignatureError.Malformed)
      }

  /** Checks the signature of the `length` protobuf bytes at `offset` (a `Message`, after any gzip is undone): the last
    * field must be the signature, and its MAC must match the bytes before it under `key` and `link` (a frame of another
    * robot, direction or epoch is `BadMac`). The replay rule is the caller's ([[ReplayWindow]]), because only the
    * caller knows the sender.
    */
  def verify(body: Array[Byte], offset: Int, length: Int, key: RobotKey, link: SignedLink)
      : Either[SignatureError, SignedBody] =
    try {
      val in = CodedInputStream.newInstance(body, offset, length)
      var signatureAt = -1
      var signature: Option[(Long, Array[Byte])] = None
      var malformed = false
      var notLast = false
      var done = false
      while (!done) {
        val at = in.getTotalBytesRead
        val tag = in.readTag()
        if (tag == 0) done = true
        else if (signatureAt >= 0) { notLast = true; done = true }
        else if (WireFormat.getTagFieldNumber(tag) == Field) {
          signatureAt = at
          if (WireFormat.getTagWireType(tag) != WireFormat.WIRETYPE_LENGTH_DELIMITED) { malformed = true; done = true }
          else {
            val limit = in.pushLimit(in.readRawVarint32())
            signature = readSignature(in)
            in.popLimit(limit)
            if (signature.isEmpty) { malformed = true; done = true }
          }
        } else in.skipField(tag)
      }
      if (notLast) Left(SignatureError.NotLast)
      else if (malformed) Left(SignatureError.Malformed)
      else
        signature match {
          case None => Left(SignatureError.Missing)
          case Some((timestamp, tag)) =>
            val expected = mac(key, link, timestamp, body, offset, signatureAt)
            if (MessageDigest.isEqual(expected, tag)) Right(SignedBody(timestamp, signatureAt))
            else Left(SignatureError.BadMac)
        }
    } catch { case NonFatal(_) => Left(SignatureError.Malformed) }

  /** The signature message: exactly one fixed64 timestamp (1) and one 8-byte mac (2); anything else is malformed. */
  private def readSignature(in: CodedInputStream): Option[(Long, Array[Byte])] = {
    var timestamp: Option[Long] = None
    var tag: Option[Array[Byte]] = None
    var ok = true
    var done = false
    while (ok && !done) {
      val t = in.readTag()
      if (t == 0) done = true
      else if (t == ((1 << 3) | WireFormat.WIRETYPE_FIXED64) && timestamp.isEmpty) timestamp = Some(in.readFixed64())
      else if (t == ((2 << 3) | WireFormat.WIRETYPE_LENGTH_DELIMITED) && tag.isEmpty) {
        val bytes = in.readByteArray()
        if (bytes.length == MacBytes) tag = Some(bytes) else ok = false
      } else ok = false
    }
    if (ok) for { ts <- timestamp; mac <- tag } yield ts -> mac else None
  }

  /** The gateway's next timestamp: microseconds since the Unix epoch, but always above the last one it used. */
  def nextGatewayTimestamp(last: Long, nowMicros: Long): Long = math.max(last + 1, nowMicros)

  /** A robot's timestamp: its boot epoch in the high 32 bits, its frame counter of this boot in the low. */
  def robotTimestamp(bootEpoch: Long, frameCounter: Long): Long =
    ((bootEpoch & 0xffffffffL) << 32) | (frameCounter & 0xffffffffL)

  /** The boot epoch a robot's timestamp carries (its high 32 bits). */
  def epochOf(robotTimestamp: Long): Int = (robotTimestamp >>> 32).toInt
}
