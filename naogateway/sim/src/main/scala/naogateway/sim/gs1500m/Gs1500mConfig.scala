package naogateway.sim.gs1500m

import scala.collection.immutable.ArraySeq

/** A UDP datagram reaching the module from the air, on connection `cid`; `remote` is the sender when the connection is
  * a UDP server (the module then frames it `ESC 'y'`), `None` for a direct connection (`ESC 'Z'`).
  */
final case class AirDatagram(cid: Int, remote: Option[Remote], payload: ArraySeq[Byte])

/** Settings of the GS1500M model.
  *
  * @param bufferBytes
  *   the one buffer shared by incoming and outgoing data (thesis §6.1: "only a 1400-byte buffer")
  * @param baud
  *   the serial line to the CM-530 (thesis §7: 460800 in every test)
  * @param bitsPerByte
  *   8N1 framing: start bit, 8 data bits, stop bit, so 460800 baud carry 46080 bytes/s
  * @param overwriteProbability
  *   when a datagram does not fit, the chance that the module overwrites the oldest unread bytes to make room instead
  *   of dropping the new datagram (the thesis saw both: "Verlust von Paketen und teilweise überschriebenen Paketen")
  * @param acknowledgeSends
  *   whether the module answers each packet it sent with `ESC 'O'` on the serial line
  * @param timeScale
  *   multiplies the serial line's durations, like [[Cm530Costs.timeScale]]
  */
final case class Gs1500mConfig(
    bufferBytes: Int = Gs1500mSerial.MaxPayload,
    baud: Int = 460800,
    bitsPerByte: Int = 10,
    overwriteProbability: Double = 0.5,
    acknowledgeSends: Boolean = true,
    timeScale: Double = 1.0
) {
  require(bufferBytes > 0 && baud > 0 && bitsPerByte > 0, "buffer, baud and bits per byte must be positive")
  require(overwriteProbability >= 0.0 && overwriteProbability <= 1.0, "overwriteProbability must be in [0, 1]")
  require(timeScale > 0.0 && !timeScale.isInfinite, s"timeScale must be positive, is $timeScale")

  /** The serial line's rate in bytes per second (46080 at the defaults). */
  def bytesPerSecond: Double = baud.toDouble / bitsPerByte

  /** Simulated nanoseconds `bytes` take on the serial line, rounded up. */
  def lineNanos(bytes: Int): Long =
    if (bytes <= 0) 0L
    else math.ceil(bytes.toDouble * bitsPerByte * 1e9 / baud * timeScale - 1e-6).toLong
}

/** One thing queued in the module for the serial line towards the CM-530. */
sealed trait RxEntry extends Product with Serializable {

  /** Space it takes in the module's data buffer. */
  def bufferBytes: Int

  /** What the CM-530 reads for it. */
  def serialBytes: ArraySeq[Byte]

  /** How many bytes the CM-530 reads for it. */
  def serialLength: Int = serialBytes.length

  /** Copies [[serialBytes]] into `out` from `at`; where the next entry's bytes go. */
  def copySerialBytes(out: Array[Byte], at: Int): Int = {
    RxEntry.copy(serialBytes, 0, out, at, serialLength)
    at + serialLength
  }
}

/** The kinds of queued entries. */
object RxEntry {

  // `n` bytes of `from` from `offset` into `out` at `at`, without boxing when `from` wraps a byte array.
  private[gs1500m] def copy(from: ArraySeq[Byte], offset: Int, out: Array[Byte], at: Int, n: Int): Unit =
    from match {
      case bytes: ArraySeq.ofByte => System.arraycopy(bytes.unsafeArray, offset, out, at, n)
      case other =>
        var i = 0
        while (i < n) { out(at + i) = other(offset + i); i += 1 }
    }

  /** A received datagram; `overwritten` bytes of its beginning are gone, and with them its header. */
  final case class Frame(id: Long, datagram: AirDatagram, header: ArraySeq[Byte], arrivedAt: Long, overwritten: Int)
      extends RxEntry {

    /** Payload bytes still in the buffer. */
    def remaining: Int = datagram.payload.length - overwritten

    def bufferBytes: Int = remaining

    def serialBytes: ArraySeq[Byte] =
      if (overwritten == 0) header ++ datagram.payload else datagram.payload.drop(overwritten)

    override def serialLength: Int = if (overwritten == 0) header.length + remaining else remaining

    // Without building the concatenation first: every received datagram is copied here.
    override def copySerialBytes(out: Array[Byte], at: Int): Int =
      if (overwritten == 0) {
        RxEntry.copy(header, 0, out, at, header.length)
        RxEntry.copy(datagram.payload, 0, out, at + header.length, remaining)
        at + header.length + remaining
      } else {
        RxEntry.copy(datagram.payload, overwritten, out, at, remaining)
        at + remaining
      }
  }

  /** A two-byte reply about a sent packet; the module makes these, they take no data buffer. */
  final case class ReplyEntry(reply: SerialEvent.Reply) extends RxEntry {
    def bufferBytes: Int = 0
    def serialBytes: ArraySeq[Byte] = ArraySeq(Gs1500mSerial.Esc, reply.letter.toByte)
    override def serialLength: Int = 2
    override def copySerialBytes(out: Array[Byte], at: Int): Int = {
      out(at) = Gs1500mSerial.Esc
      out(at + 1) = reply.letter.toByte
      at + 2
    }
  }

  /** A text status line (with its CR LF); the module makes these, they take no data buffer. */
  final case class StatusEntry(text: String, serialBytes: ArraySeq[Byte]) extends RxEntry {
    def bufferBytes: Int = 0
  }
}

/** Incoming payload crossing the serial line to the CM-530: its buffer space frees evenly between start and end. */
final case class Drain(payloadBytes: Int, startsAt: Long, endsAt: Long) {

  /** Payload bytes of this read still in the module at `t`. */
  def remainingAt(t: Long): Int =
    if (t <= startsAt) payloadBytes
    else if (t >= endsAt) 0
    else math.ceil(payloadBytes.toDouble * (endsAt - t) / (endsAt - startsAt)).toInt
}

/** A packet the CM-530 hands to the module: it holds buffer space until its last byte has crossed the serial line at
  * `endsAt`, when it goes on air.
  */
final case class TxEntry(cid: Int, data: ArraySeq[Byte], startsAt: Long, endsAt: Long)
