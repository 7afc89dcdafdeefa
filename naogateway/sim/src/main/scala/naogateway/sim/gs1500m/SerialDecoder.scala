package naogateway.sim.gs1500m

import scala.collection.immutable.ArraySeq

import naogateway.sim.gs1500m.SerialEvent._

/** An incremental, immutable parser of the byte stream the GS1500M writes to the CM-530 (docs/protocol.md §12),
  * modelled on the thesis's polled state machine (§5.2.2).
  *
  * Feed it chunks of any size; it returns the next decoder and the events completed by that chunk. It never throws:
  * bytes that fit no item are counted and reported as one [[SerialEvent.Garbage]] in front of the next item. How it
  * resynchronises:
  *   - an `ESC` always starts a new item, wherever it appears outside a datagram's data (bulk data carries no escaping,
  *     so inside the announced length nothing is special);
  *   - a header that turns out malformed (bad cid, non-digit in the length, a length over 1400, no TAB within
  *     [[Gs1500mSerial.MaxAddressChars]]) becomes garbage, and so does everything after it up to the next `ESC` or LF
  *     (the LF ends a broken status line, so the next line is read again);
  *   - `ESC` followed by any other ASCII letter than `Z`/`y` is a two-byte reply, as in the thesis; followed by a
  *     non-letter, the `ESC` alone is garbage and the byte is read afresh.
  *
  * Text lines end at LF; CRs before it are dropped and empty lines are skipped, because the module pads its replies
  * with extra line ends. A line with a non-printable byte is garbage.
  *
  * Chunking never changes the result: the events of one call on the whole input equal the concatenated events of calls
  * on any split of it.
  */
final class SerialDecoder private (
    private val mode: SerialDecoder.Mode,
    /** Garbage bytes counted but not yet reported (they are reported in front of the next item). */
    val pendingGarbage: Int,
    /** Data longer than this is taken for a corrupt header. */
    val maxPayload: Int
) {
  import SerialDecoder._

  /** Whether the decoder is between items with nothing pending. */
  def isIdle: Boolean = mode == Idle && pendingGarbage == 0

  /** Decodes the next chunk of serial bytes. */
  def feed(chunk: Array[Byte]): (SerialDecoder, Vector[SerialEvent]) = run(chunk)

  /** Decodes the next chunk of serial bytes. */
  def feed(chunk: ArraySeq[Byte]): (SerialDecoder, Vector[SerialEvent]) = chunk match {
    case bytes: ArraySeq.ofByte => run(bytes.unsafeArray)
    case other                  => run(other.toArray)
  }

  // Local mutable machinery only: every call starts from this immutable snapshot and ends in a fresh one.
  private def run(chunk: Array[Byte]): (SerialDecoder, Vector[SerialEvent]) = {
    val out = Vector.newBuilder[SerialEvent]
    var garbage = pendingGarbage
    var state: Mode = mode
    val text = new java.lang.StringBuilder
    var payload: Array[Byte] = null
    var filled = 0

    state match {
      case Text(s)       => text.append(s)
      case Address(_, s) => text.append(s)
      case Payload(_, _, need, got) =>
        payload = new Array[Byte](need)
        got.copyToArray(payload)
        filled = got.length
      case _ =>
    }

    def emit(event: SerialEvent): Unit = {
      if (garbage > 0) { out += Garbage(garbage); garbage = 0 }
      out += event
    }

    // A header or line broke at byte `b` after `consumed` good-looking bytes: all of them are garbage, and so is
    // what follows up to the next ESC or LF.
    def skip(consumed: Int, b: Int): Unit = {
      garbage += consumed
      if (b == Gs1500mSerial.Esc) state = Escape
      else if (b == '\n') { garbage += 1; state = Idle }
      else { garbage += 1; state = Skipping }
    }

    def idle(b: Int): Unit =
      if (b == Gs1500mSerial.Esc) state = Escape
      else if (b == '\r' || b == '\n') ()
      else if (Gs1500mSerial.isTextByte(b)) { text.setLength(0); text.append(b.toChar); state = Text("") }
      else { garbage += 1; state = Skipping }

    def startPayload(cid: Int, remote: Option[Remote], length: Int): Unit =
      if (length == 0) { emit(Data(cid, remote, ArraySeq.empty[Byte])); state = Idle }
      else { payload = new Array[Byte](length); filled = 0; state = Payload(cid, remote, length, ArraySeq.empty) }

    def step(b: Int): Unit = state match {
      case Idle => idle(b)
      case Skipping =>
        if (b == Gs1500mSerial.Esc) state = Escape
        else if (b == '\n') { garbage += 1; state = Idle }
        else garbage += 1
      case Text(_) =>
        if (b == '\n') {
          var end = text.length
          while (end > 0 && text.charAt(end - 1) == '\r') end -= 1
          val line = text.substring(0, end)
          if (line.nonEmpty) emit(StatusLine(line))
          state = Idle
        } else if (Gs1500mSerial.isTextByte(b) && text.length < Gs1500mSerial.MaxStatusLineChars) text.append(b.toChar)
        else skip(text.length, b)
      case Escape =>
        if (b == 'Z'.toInt || b == 'y'.toInt) state = CidNext(b == 'y'.toInt)
        else if (b == Gs1500mSerial.Esc) garbage += 1
        else if (b < 128 && Gs1500mSerial.isReplyLetter(b.toChar)) {
          emit(b.toChar match {
            case 'O' => Ack
            case 'F' => Fail
            case c   => OtherReply(c)
          })
          state = Idle
        } else { garbage += 1; state = Idle; idle(b) }
      case CidNext(udpServer) =>
        val cid = Gs1500mSerial.parseCid(b)
        if (cid < 0) skip(2, b)
        else if (udpServer) { text.setLength(0); state = Address(cid, "") }
        else state = Length(cid, None, 0, 0, 3)
      case Address(cid, _) =>
        if (b == '\t')
          state = Length(cid, Gs1500mSerial.parseAddressField(text.toString), 0, 0, 4 + text.length)
        else if (b >= 0x20 && b <= 0x7e && text.length < Gs1500mSerial.MaxAddressChars) text.append(b.toChar)
        else skip(3 + text.length, b)
      case Length(cid, remote, digits, value, consumed) =>
        if (b >= '0' && b <= '9') {
          val v = value * 10 + (b - '0')
          if (digits < 3) state = Length(cid, remote, digits + 1, v, consumed + 1)
          else if (v > maxPayload) { garbage += consumed + 1; state = Skipping }
          else startPayload(cid, remote, v)
        } else skip(consumed, b)
      case Payload(_, _, _, _) => () // consumed in bulk by the loop below
    }

    var i = 0
    while (i < chunk.length) state match {
      case Payload(cid, remote, need, _) =>
        val take = math.min(need - filled, chunk.length - i)
        System.arraycopy(chunk, i, payload, filled, take)
        filled += take
        i += take
        if (filled == need) {
          emit(Data(cid, remote, ArraySeq.unsafeWrapArray(payload)))
          payload = null
          state = Idle
        }
      case _ =>
        step(chunk(i) & 0xff)
        i += 1
    }

    val snapshot: Mode = state match {
      case Text(_)                       => Text(text.toString)
      case Address(cid, _)               => Address(cid, text.toString)
      case Payload(cid, remote, need, _) => Payload(cid, remote, need, ArraySeq.unsafeWrapArray(payload.take(filled)))
      case other                         => other
    }
    (new SerialDecoder(snapshot, garbage, maxPayload), out.result())
  }

  override def toString: String = s"SerialDecoder($mode, pendingGarbage = $pendingGarbage)"

  // Value equality, so models holding a decoder compare (and replay-check) as values.
  override def equals(other: Any): Boolean = other match {
    case d: SerialDecoder => d.mode == mode && d.pendingGarbage == pendingGarbage && d.maxPayload == maxPayload
    case _                => false
  }

  override def hashCode: Int = (mode, pendingGarbage, maxPayload).##
}

/** Where a fresh decoder comes from. */
object SerialDecoder {

  /** A decoder at the start of a stream, taking data up to the module's 1400 bytes. */
  val empty: SerialDecoder = new SerialDecoder(Idle, 0, Gs1500mSerial.MaxPayload)

  /** A decoder at the start of a stream that takes announced lengths up to `maxPayload` (at most 9999). */
  def withMaxPayload(maxPayload: Int): SerialDecoder =
    new SerialDecoder(Idle, 0, math.max(0, math.min(maxPayload, 9999)))

  /** Decodes a whole stream at once; what is still incomplete at its end is left out. */
  def decodeAll(bytes: Array[Byte]): Vector[SerialEvent] = empty.feed(bytes)._2

  private[gs1500m] sealed trait Mode extends Product with Serializable
  private case object Idle extends Mode
  private case object Skipping extends Mode
  private case object Escape extends Mode
  private final case class Text(soFar: String) extends Mode
  private final case class CidNext(udpServer: Boolean) extends Mode
  private final case class Address(cid: Int, soFar: String) extends Mode
  private final case class Length(cid: Int, remote: Option[Remote], digits: Int, value: Int, consumed: Int)
      extends Mode
  private final case class Payload(cid: Int, remote: Option[Remote], need: Int, got: ArraySeq[Byte]) extends Mode
}
