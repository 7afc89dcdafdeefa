package naogateway.gateway.recording

import java.io.IOException
import java.nio.charset.StandardCharsets
import java.util.zip.CRC32

/** The MCAP container format (version 0), as far as the gateway's recordings need it: written and read from the
  * published specification. Little-endian numbers; strings, maps and arrays carry a `u32` byte length; every record is
  * `<u8 opcode><u64 content length><content>`.
  *
  * A file this writer makes: magic, Header, uncompressed Chunks (each holding the Schema, Channel and Message records
  * of its time, followed by one Message Index per channel in it), Data End (with the CRC of every byte before it), the
  * Summary (Schemas, Channels, Chunk Indexes, Statistics, each group once), the Summary Offsets, the Footer (with the
  * CRC of the summary) and the magic again. Pure code: no actor, no thread.
  */
object Mcap {

  /** The 8 bytes that open and close every MCAP file: 0x89 "MCAP" '0' CR LF. */
  val Magic: Array[Byte] = Array(0x89.toByte, 'M', 'C', 'A', 'P', '0', '\r', '\n').map(_.toByte)

  /** Record opcodes. */
  object Op {
    val Header: Int = 0x01
    val Footer: Int = 0x02
    val Schema: Int = 0x03
    val Channel: Int = 0x04
    val Message: Int = 0x05
    val Chunk: Int = 0x06
    val MessageIndex: Int = 0x07
    val ChunkIndex: Int = 0x08
    val Statistics: Int = 0x0b
    val SummaryOffset: Int = 0x0e
    val DataEnd: Int = 0x0f
  }

  /** A schema: `name` is the message type, `encoding` how `data` describes it ("protobuf": a FileDescriptorSet). */
  final case class Schema(id: Int, name: String, encoding: String, data: Array[Byte])

  /** A channel: a topic with its message encoding and schema (0: none). */
  final case class Channel(id: Int, schemaId: Int, topic: String, messageEncoding: String,
      metadata: Map[String, String])

  /** One message: times are nanoseconds since the Unix epoch. */
  final case class Message(channelId: Int, sequence: Long, logTime: Long, publishTime: Long, data: Array[Byte])

  /** A file's contents as [[McapReader]] finds them. */
  final case class Contents(
      profile: String,
      library: String,
      schemas: Map[Int, Schema],
      channels: Map[Int, Channel],
      messages: Vector[Message],
      statistics: Option[Statistics]
  )

  /** The Statistics record: counts and the time span of the file's messages. */
  final case class Statistics(
      messageCount: Long,
      schemaCount: Int,
      channelCount: Int,
      chunkCount: Int,
      messageStartTime: Long,
      messageEndTime: Long,
      channelMessageCounts: Map[Int, Long]
  )

  /** A file that is not MCAP, or not one this reader understands. */
  final class FormatException(message: String) extends IOException(message)

  /** A growable little-endian byte buffer. */
  private[recording] final class Buffer(initial: Int = 256) {
    private var bytes = new Array[Byte](math.max(16, initial))
    private var size = 0

    def length: Int = size
    def array: Array[Byte] = bytes
    def clear(): Unit = size = 0
    def toArray: Array[Byte] = java.util.Arrays.copyOf(bytes, size)

    private def room(n: Int): Unit =
      if (size + n > bytes.length) bytes = java.util.Arrays.copyOf(bytes, math.max(bytes.length * 2, size + n))

    def u8(v: Int): Buffer = { room(1); bytes(size) = v.toByte; size += 1; this }
    def u16(v: Int): Buffer = { room(2); put16(v); this }
    def u32(v: Long): Buffer = { room(4); put32(v.toInt); this }
    def u64(v: Long): Buffer = { room(8); put32(v.toInt); put32((v >>> 32).toInt); this }

    /** A Message record's head: opcode, content length (for `n` bytes of data), channel id, sequence, log time and
      * publish time, with room for the data checked once.
      */
    def messageHead(channelId: Int, sequence: Long, logTime: Long, publishTime: Long, n: Int): Buffer = {
      room(1 + 8 + 2 + 4 + 8 + 8 + n)
      bytes(size) = Mcap.Op.Message.toByte
      size += 1
      val length = 2L + 4L + 8L + 8L + n
      put32(length.toInt); put32((length >>> 32).toInt)
      put16(channelId)
      put32(sequence.toInt)
      put32(logTime.toInt); put32((logTime >>> 32).toInt)
      put32(publishTime.toInt); put32((publishTime >>> 32).toInt)
      this
    }

    private def put16(v: Int): Unit = {
      bytes(size) = v.toByte
      bytes(size + 1) = (v >>> 8).toByte
      size += 2
    }

    private def put32(v: Int): Unit = {
      val at = size
      bytes(at) = v.toByte
      bytes(at + 1) = (v >>> 8).toByte
      bytes(at + 2) = (v >>> 16).toByte
      bytes(at + 3) = (v >>> 24).toByte
      size = at + 4
    }
    def raw(b: Array[Byte]): Buffer = raw(b, 0, b.length)
    def raw(b: Array[Byte], from: Int, n: Int): Buffer = {
      room(n); System.arraycopy(b, from, bytes, size, n); size += n; this
    }
    def string(s: String): Buffer = { val b = s.getBytes(StandardCharsets.UTF_8); u32(b.length.toLong); raw(b) }
    def setU64(at: Int, v: Long): Unit = { var i = 0; while (i < 8) { bytes(at + i) = (v >>> (8 * i)).toByte; i += 1 } }

    /** A record of `op` whose content `body` writes; its length is filled in afterwards. */
    def record(op: Int)(body: Buffer => Unit): Buffer = {
      u8(op)
      val lengthAt = size
      u64(0L)
      body(this)
      setU64(lengthAt, (size - lengthAt - 8).toLong)
      this
    }

    def map(entries: Iterable[(String, String)]): Buffer = {
      val start = size
      u32(0L)
      entries.foreach { case (k, v) => string(k); string(v) }
      setU32(start, (size - start - 4).toLong)
      this
    }

    def setU32(at: Int, v: Long): Unit = { var i = 0; while (i < 4) { bytes(at + i) = (v >>> (8 * i)).toByte; i += 1 } }
  }

  /** A growable list of ints, without boxing. */
  private[recording] final class IntList {
    private var values = new Array[Int](16)
    private var n = 0

    def size: Int = n
    def apply(i: Int): Int = values(i)
    def clear(): Unit = n = 0
    def add(v: Int): Unit = {
      if (n == values.length) values = java.util.Arrays.copyOf(values, n * 2)
      values(n) = v
      n += 1
    }
    def foreach(f: Int => Unit): Unit = { var i = 0; while (i < n) { f(values(i)); i += 1 } }
  }

  /** Reads little-endian fields out of a record's content. */
  private[recording] final class Fields(bytes: Array[Byte], from: Int, until: Int) {
    private var at = from

    def position: Int = at
    def remaining: Int = until - at
    private def need(n: Int): Unit =
      if (n < 0 || at + n > until) throw new FormatException(s"record ends after ${at - from} bytes, $n more needed")
    private def le(n: Int): Long = {
      need(n)
      var v = 0L
      var i = 0
      while (i < n) { v |= (bytes(at + i) & 0xffL) << (8 * i); i += 1 }
      at += n
      v
    }
    def u8(): Int = le(1).toInt
    def u16(): Int = le(2).toInt
    def u32(): Long = le(4)
    def u64(): Long = le(8)
    def raw(n: Int): Array[Byte] = { need(n); val b = java.util.Arrays.copyOfRange(bytes, at, at + n); at += n; b }
    def rest(): Array[Byte] = raw(until - at)
    def string(): String = {
      val n = lengthOf(u32()); need(n); val s = new String(bytes, at, n, StandardCharsets.UTF_8); at += n; s
    }
    def stringMap(): Map[String, String] = {
      val length = lengthOf(u32())
      val end = at + length
      need(end - at)
      val m = Map.newBuilder[String, String]
      while (at < end) m += string() -> string()
      m.result()
    }
    def countMap(): Map[Int, Long] = {
      val length = lengthOf(u32())
      val end = at + length
      need(end - at)
      val m = Map.newBuilder[Int, Long]
      while (at < end) m += u16() -> u64()
      m.result()
    }
    def lengthOf(n: Long): Int =
      if (n < 0 || n > Int.MaxValue) throw new FormatException(s"length $n is beyond what this reader takes")
      else n.toInt
  }

  /** The CRC-32 (ISO-HDLC, as zlib's) of `bytes[from, from + n)`. */
  def crc(bytes: Array[Byte], from: Int, n: Int): Long = {
    val c = new CRC32
    c.update(bytes, from, n)
    c.getValue
  }
}
