package naogateway.sim.gs1500m

import scala.collection.immutable.ArraySeq

/** A peer's IPv4 address and UDP port, as a GS1500M UDP server reports them in front of a received datagram. */
final case class Remote(ip: String, port: Int)

/** Anything the serial decoder recognises in the byte stream the GS1500M writes to the CM-530. */
sealed trait SerialEvent extends Product with Serializable

/** A well-formed piece of the serial stream: what the decoder yields besides garbage, and what the encoder takes. */
sealed trait SerialItem extends SerialEvent

/** The pieces of the GS1500M serial stream in bulk data mode (docs/protocol.md §12). */
object SerialEvent {

  /** One datagram on connection `cid`; `remote` is the sender when it came through a UDP server (`ESC 'y'`), else
    * `None` (`ESC 'Z'`, also the form the CM-530 sends in).
    */
  final case class Data(cid: Int, remote: Option[Remote], bytes: ArraySeq[Byte]) extends SerialItem

  /** A two-byte `ESC` + letter reply about a packet the CM-530 handed to the module; a UDP user ignores it. */
  sealed trait Reply extends SerialItem {

    /** The letter after `ESC`. */
    def letter: Char
  }

  /** `ESC 'O'`: the module sent the packet (not that anyone received it). */
  case object Ack extends Reply {
    val letter: Char = 'O'
  }

  /** `ESC 'F'`: the module failed to send the packet. */
  case object Fail extends Reply {
    val letter: Char = 'F'
  }

  /** `ESC` and an ASCII letter other than `Z`, `y`, `O`, `F`: a reply the thesis's parser drops like the others. */
  final case class OtherReply(letter: Char) extends Reply

  /** A text line from the module without its CR LF, e.g. `CONNECT 0` or `DISCONNECT 0`. */
  final case class StatusLine(text: String) extends SerialItem

  /** `count` bytes that fit no item (e.g. the tail of a datagram whose beginning was overwritten in the module). */
  final case class Garbage(count: Int) extends SerialEvent
}

/** Why an item cannot be put on the serial line. */
sealed trait SerialError extends Product with Serializable {

  /** A short text for logs. */
  def describe: String
}

/** Every way the encoder refuses an item. */
object SerialError {

  /** The connection number is outside 0–15. */
  final case class BadCid(cid: Int) extends SerialError {
    def describe: String = s"connection id $cid is outside 0..${Gs1500mSerial.MaxCid}"
  }

  /** More data than the module's 1400-byte buffer takes. */
  final case class TooLong(length: Int, limit: Int) extends SerialError {
    def describe: String = s"$length bytes exceed the module's $limit-byte buffer"
  }

  /** The sender address is not a dotted IPv4 address with a port in 0–65535. */
  final case class BadRemote(remote: Remote) extends SerialError {
    def describe: String = s"cannot frame sender $remote"
  }

  /** A status line must be printable ASCII, non-empty, without CR or LF, and not too long. */
  final case class BadStatusLine(text: String) extends SerialError {
    def describe: String = s"not a status line: ${text.take(40)}"
  }

  /** A reply letter must be an ASCII letter other than `Z`, `y` (data headers), and `O`/`F` only as Ack/Fail. */
  final case class BadReplyLetter(letter: Char) extends SerialError {
    def describe: String = s"'$letter' cannot follow ESC as a reply"
  }
}

/** Encoding of the GS1500M's serial framing in bulk data mode (docs/protocol.md §12; thesis §5.2.2, §5.3).
  *
  *   - Bulk send and direct receive: `ESC 'Z' <cid> <length as 4 ASCII digits> <data>`, no trailer.
  *   - UDP server receive: `ESC 'y' <cid> <ip> ' ' <port> TAB <length as 4 ASCII digits> <data>`. The thesis only says
  *     that ip and port have variable length and that its parser waits for the TAB before the length; the separator
  *     between them and their spelling are the GainSpan adapter guide's (`<IP address><space><port><horizontal tab>`):
  *     the ip in dotted decimal without leading zeros, one space, the port in decimal without leading zeros. The
  *     decoder is more lenient (see [[SerialDecoder]]).
  *   - Replies: `ESC` + one letter (`O` success, `F` failure).
  *   - Status lines: printable text ended by CR LF.
  */
object Gs1500mSerial {

  /** The escape byte that starts every binary item. */
  val Esc: Byte = 27

  /** Letter of the bulk send / direct receive header. */
  val BulkLetter: Char = 'Z'

  /** Letter of the UDP server receive header. */
  val UdpServerLetter: Char = 'y'

  /** The module's buffer, and so the largest datagram it sends or receives. */
  val MaxPayload: Int = 1400

  /** Connection numbers are one hex digit: up to 16 connections. */
  val MaxCid: Int = 15

  /** Bytes of `ESC 'Z' <cid> <len4>`. */
  val BulkHeaderBytes: Int = 7

  /** The thesis sizes its receive buffer for "up to 39 bytes of receive header"; with the 8 fixed bytes of the `ESC
    * 'y'` header that leaves 31 characters for ip, separator and port, so the decoder gives up beyond that.
    */
  val MaxAddressChars: Int = 31

  /** Longer text without CR LF is taken for garbage; the module's status lines are far shorter. */
  val MaxStatusLineChars: Int = 256

  /** The hex digit naming connection `cid` (lower case, as the module prints it). */
  def cidChar(cid: Int): Either[SerialError, Char] =
    if (cid < 0 || cid > MaxCid) Left(SerialError.BadCid(cid))
    else Right(Character.forDigit(cid, 16))

  /** The connection number of a cid byte (either case accepted), or -1. */
  def parseCid(b: Int): Int =
    if (b >= '0' && b <= '9') b - '0'
    else if (b >= 'a' && b <= 'f') b - 'a' + 10
    else if (b >= 'A' && b <= 'F') b - 'A' + 10
    else -1

  /** `ESC 'Z' <cid> <len4>`: the 7 bytes in front of `length` bytes of bulk data. */
  def bulkHeader(cid: Int, length: Int): Either[SerialError, ArraySeq[Byte]] =
    if (cid < 0 || cid > MaxCid) Left(SerialError.BadCid(cid))
    else if (length < 0 || length > MaxPayload) Left(SerialError.TooLong(length, MaxPayload))
    else {
      // Built by hand: every datagram the CM-530 sends passes here.
      val out = new Array[Byte](BulkHeaderBytes)
      out(0) = Esc
      out(1) = BulkLetter.toByte
      out(2) = Character.forDigit(cid, 16).toByte
      putLen4(out, 3, length)
      Right(ArraySeq.unsafeWrapArray(out))
    }

  /** `ESC 'y' <cid> <ip> ' ' <port> TAB <len4>`: the header of a datagram a UDP server received from `remote`. */
  def udpServerHeader(cid: Int, remote: Remote, length: Int): Either[SerialError, ArraySeq[Byte]] =
    if (cid < 0 || cid > MaxCid) Left(SerialError.BadCid(cid))
    else if (length < 0 || length > MaxPayload) Left(SerialError.TooLong(length, MaxPayload))
    else if (!isDottedIpv4(remote.ip) || remote.port < 0 || remote.port > 65535) Left(SerialError.BadRemote(remote))
    else {
      val ip = remote.ip
      val port = Integer.toString(remote.port)
      val out = new Array[Byte](3 + ip.length + 1 + port.length + 1 + 4)
      out(0) = Esc
      out(1) = UdpServerLetter.toByte
      out(2) = Character.forDigit(cid, 16).toByte
      var at = 3
      var i = 0
      while (i < ip.length) { out(at) = ip.charAt(i).toByte; at += 1; i += 1 }
      out(at) = ' '.toByte
      at += 1
      i = 0
      while (i < port.length) { out(at) = port.charAt(i).toByte; at += 1; i += 1 }
      out(at) = '\t'.toByte
      putLen4(out, at + 1, length)
      Right(ArraySeq.unsafeWrapArray(out))
    }

  /** A whole bulk frame: what the CM-530 sends, and what it receives on a direct connection. */
  def encodeBulk(cid: Int, data: ArraySeq[Byte]): Either[SerialError, ArraySeq[Byte]] =
    bulkHeader(cid, data.length).map(_ ++ data)

  /** The bytes of one item on the serial line. */
  def encode(item: SerialItem): Either[SerialError, ArraySeq[Byte]] =
    item match {
      case SerialEvent.Data(cid, None, bytes)         => encodeBulk(cid, bytes)
      case SerialEvent.Data(cid, Some(remote), bytes) => udpServerHeader(cid, remote, bytes.length).map(_ ++ bytes)
      case SerialEvent.Ack                            => Right(reply('O'))
      case SerialEvent.Fail                           => Right(reply('F'))
      case SerialEvent.OtherReply(letter) =>
        if (isReplyLetter(letter) && letter != 'O' && letter != 'F') Right(reply(letter))
        else Left(SerialError.BadReplyLetter(letter))
      case SerialEvent.StatusLine(text) =>
        if (text.nonEmpty && text.length <= MaxStatusLineChars && text.forall(c => isTextByte(c.toInt) && c != '\r'))
          Right(ascii(text + "\r\n"))
        else Left(SerialError.BadStatusLine(text))
    }

  /** Serial bytes of a whole header for `data` of `remote` (`None`: the direct form), without the data. */
  def headerBytes(cid: Int, remote: Option[Remote], length: Int): Either[SerialError, ArraySeq[Byte]] =
    remote.fold(bulkHeader(cid, length))(udpServerHeader(cid, _, length))

  /** Whether `b` may stand in a status line (printable ASCII, TAB, or a CR before the LF). */
  def isTextByte(b: Int): Boolean = (b >= 0x20 && b <= 0x7e) || b == '\t' || b == '\r'

  /** Whether `ESC` followed by `c` is a two-byte reply rather than a data header. */
  def isReplyLetter(c: Char): Boolean =
    ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z')) && c != BulkLetter && c != UdpServerLetter

  /** Reads the text between cid and TAB of an `ESC 'y'` header; `None` when it is not `<ip><sep><port>`.
    *
    * Accepts a space (the module's form) or a colon between ip and port, so a header from a differently configured
    * module still yields its sender; anything else still delivers the data, just without a sender.
    */
  def parseAddressField(field: String): Option[Remote] = {
    val cut = math.max(field.lastIndexOf(' '), field.lastIndexOf(':'))
    if (cut <= 0 || cut == field.length - 1) None
    else {
      val ip = field.substring(0, cut)
      val port = field.substring(cut + 1)
      if (port.length <= 5 && port.forall(c => c >= '0' && c <= '9') && port.toInt <= 65535 && !ip.contains(' '))
        Some(Remote(ip, port.toInt))
      else None
    }
  }

  // Four octets of plain decimal 0..255 without leading zeros, separated by dots, as the module prints an address.
  private def isDottedIpv4(ip: String): Boolean = {
    var octets = 0
    var digits = 0
    var value = 0
    var leadingZero = false
    var ok = true
    var i = 0
    while (ok && i <= ip.length) {
      val c = if (i == ip.length) '.' else ip.charAt(i)
      if (c == '.') {
        ok = digits > 0
        octets += 1
        digits = 0
        value = 0
      } else if (c >= '0' && c <= '9') {
        if (digits == 0) leadingZero = c == '0'
        else ok = !leadingZero
        digits += 1
        value = value * 10 + (c - '0')
        ok = ok && digits <= 3 && value <= 255
      } else ok = false
      i += 1
    }
    ok && octets == 4
  }

  // The length as exactly four ASCII digits (at most 1400, checked before).
  private def putLen4(out: Array[Byte], at: Int, length: Int): Unit = {
    out(at) = ('0' + length / 1000 % 10).toByte
    out(at + 1) = ('0' + length / 100 % 10).toByte
    out(at + 2) = ('0' + length / 10 % 10).toByte
    out(at + 3) = ('0' + length % 10).toByte
  }

  private def reply(letter: Char): ArraySeq[Byte] = ArraySeq(Esc, letter.toByte)

  private def ascii(s: String): ArraySeq[Byte] =
    ArraySeq.unsafeWrapArray(s.getBytes(java.nio.charset.StandardCharsets.ISO_8859_1))
}
