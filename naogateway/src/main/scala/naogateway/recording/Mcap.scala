package naogateway.recording

import java.io.{EOFException, IOException, InputStream, OutputStream}
import java.nio.charset.StandardCharsets
import java.util.zip.CRC32

import scala.collection.mutable

/**
 * The MCAP container format (version 0), as far as the gateway's recordings need it: written and read from the
 * published specification. Little-endian numbers; strings, maps and arrays carry a `u32` byte length; every record is
 * `<u8 opcode><u64 content length><content>`.
 *
 * A file this writer makes: magic, Header, uncompressed Chunks (each holding the Schema, Channel and Message records
 * of its time, followed by one Message Index per channel in it), Data End (with the CRC of every byte before it),
 * the Summary (Schemas, Channels, Chunk Indexes, Statistics, each group once), the Summary Offsets, the Footer (with
 * the CRC of the summary) and the magic again. Pure code: no actor, no thread.
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
  final case class Channel(id: Int, schemaId: Int, topic: String, messageEncoding: String, metadata: Map[String, String])

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

    /**
     * A Message record's head: opcode, content length (for `n` bytes of data), channel id, sequence, log time and
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
    def raw(b: Array[Byte], from: Int, n: Int): Buffer = { room(n); System.arraycopy(b, from, bytes, size, n); size += n; this }
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
    def string(): String = { val n = lengthOf(u32()); need(n); val s = new String(bytes, at, n, StandardCharsets.UTF_8); at += n; s }
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
      if (n < 0 || n > Int.MaxValue) throw new FormatException(s"length $n is beyond what this reader takes") else n.toInt
  }

  /** The CRC-32 (ISO-HDLC, as zlib's) of `bytes[from, from + n)`. */
  def crc(bytes: Array[Byte], from: Int, n: Int): Long = {
    val c = new CRC32
    c.update(bytes, from, n)
    c.getValue
  }
}

/**
 * Writes one MCAP file to `out`, which it owns and closes. Messages are gathered into uncompressed chunks of about
 * `chunkBytes`, each followed by its message indexes, so readers can seek by time; [[close]] writes the summary
 * and the footer. Not thread-safe: one writer thread.
 *
 * @param profile the Header's profile ("" for none)
 * @param library the Header's library text: who wrote the file
 */
final class McapWriter(out: OutputStream, profile: String, library: String, chunkBytes: Int = 256 * 1024) {
  import Mcap._

  require(chunkBytes >= 1024, "chunks of at least 1 KiB")

  private val crc = new CRC32
  private var written = 0L
  private val schemas = mutable.LinkedHashMap.empty[Int, Schema]
  private val channels = mutable.LinkedHashMap.empty[Int, Channel]
  // Per channel id, messages written so far; and the channels in the order of their first message (the Statistics').
  private var messageCounts = new Array[Long](64)
  private val countedChannels = new IntList
  private var messageCount = 0L
  private var firstTime = Long.MaxValue
  private var lastTime = Long.MinValue
  private val scratch = new Buffer(4096)
  private var closed = false

  // The chunk being filled, its time span and per channel the (log time, offset) of each of its messages.
  private val chunk = new Buffer(chunkBytes + chunkBytes / 4)
  private var chunkStart = Long.MaxValue
  private var chunkEnd = Long.MinValue
  // Per channel id, the message index entries of the chunk (buffers kept from chunk to chunk); the channels in the
  // order of their first message in the chunk.
  private var chunkIndex = new Array[Buffer](64)
  private val indexedChannels = new IntList
  private val chunkIndexes = new Buffer(1024)
  private var chunkCount = 0

  emit(Magic)
  emitRecord(Op.Header) { b => b.string(profile); b.string(library) }

  /** Bytes written so far plus the chunk being filled: what the file will hold before its summary. */
  def size: Long = written + chunk.length

  /** Messages written so far. */
  def messages: Long = messageCount

  /** Adds a schema and answers its id (1, 2, ...). */
  def addSchema(name: String, encoding: String, data: Array[Byte]): Int = {
    val s = Schema(schemas.size + 1, name, encoding, data)
    schemas(s.id) = s
    writeSchema(chunk, s)
    s.id
  }

  /** Adds a channel on schema `schemaId` (0: none) and answers its id (1, 2, ...). */
  def addChannel(topic: String, messageEncoding: String, schemaId: Int, metadata: Map[String, String] = Map.empty): Int = {
    require(schemaId == 0 || schemas.contains(schemaId), s"no schema $schemaId")
    require(channels.size < 65535, "an MCAP file holds at most 65535 channels")
    val c = Channel(channels.size + 1, schemaId, topic, messageEncoding, metadata)
    channels(c.id) = c
    writeChannel(chunk, c)
    c.id
  }

  /** Writes one message on `channelId`; `data` is copied. */
  def write(channelId: Int, logTime: Long, publishTime: Long, data: Array[Byte]): Unit = write(channelId, logTime, publishTime, data, 0, data.length)

  /** Writes one message whose data are `data[from, from + n)`. */
  def write(channelId: Int, logTime: Long, publishTime: Long, data: Array[Byte], from: Int, n: Int): Unit = {
    require(!closed, "the writer is closed")
    // Channel ids are given out in order from 1: the id is known when it is at most the number of channels.
    require(channelId >= 1 && channelId <= channels.size, s"no channel $channelId")
    if (channelId >= messageCounts.length) {
      val size = math.max(messageCounts.length * 2, channelId + 1)
      messageCounts = java.util.Arrays.copyOf(messageCounts, size)
      chunkIndex = java.util.Arrays.copyOf(chunkIndex, size)
    }
    val count = messageCounts(channelId) + 1
    if (count == 1) countedChannels.add(channelId)
    messageCounts(channelId) = count
    messageCount += 1
    if (logTime < firstTime) firstTime = logTime
    if (logTime > lastTime) lastTime = logTime
    if (logTime < chunkStart) chunkStart = logTime
    if (logTime > chunkEnd) chunkEnd = logTime
    var index = chunkIndex(channelId)
    if (index eq null) { index = new Buffer(256); chunkIndex(channelId) = index }
    if (index.length == 0) indexedChannels.add(channelId)
    index.u64(logTime).u64(chunk.length.toLong)
    chunk.messageHead(channelId, count & 0xffffffffL, logTime, publishTime, n).raw(data, from, n)
    if (chunk.length >= chunkBytes) flushChunk()
  }

  /** Ends the chunk being filled (if it holds anything) and flushes `out`: what was written so far is on its way to disk. */
  def flush(): Unit = if (!closed) {
    flushChunk()
    out.flush()
  }

  /** Ends the file: the last chunk, Data End, the summary, the footer; then closes `out`. Idempotent. */
  def close(): Unit = if (!closed) {
    closed = true
    try {
      flushChunk()
      emitRecord(Op.DataEnd)(_.u32(crc.getValue))
      val summaryStart = written
      crc.reset()
      val offsets = Vector.newBuilder[(Int, Long, Long)]
      def group(op: Int)(body: => Unit): Unit = {
        val start = written
        body
        if (written > start) offsets += ((op, start, written - start))
      }
      group(Op.Schema)(schemas.values.foreach(s => { scratch.clear(); writeSchema(scratch, s); emit(scratch.array, scratch.length) }))
      group(Op.Channel)(channels.values.foreach(c => { scratch.clear(); writeChannel(scratch, c); emit(scratch.array, scratch.length) }))
      group(Op.ChunkIndex)(emit(chunkIndexes.array, chunkIndexes.length))
      group(Op.Statistics)(emitRecord(Op.Statistics) { b =>
        b.u64(messageCount).u16(schemas.size).u32(channels.size.toLong).u32(0L).u32(0L).u32(chunkCount.toLong)
        b.u64(if (messageCount == 0) 0L else firstTime).u64(if (messageCount == 0) 0L else lastTime)
        val start = b.length
        b.u32(0L)
        countedChannels.foreach(id => b.u16(id).u64(messageCounts(id)))
        b.setU32(start, (b.length - start - 4).toLong)
      })
      val summaryOffsetStart = written
      offsets.result().foreach { case (op, start, length) => emitRecord(Op.SummaryOffset)(_.u8(op).u64(start).u64(length)) }
      // The footer's CRC covers the summary, the summary offsets and the footer up to its own CRC field.
      scratch.clear()
      scratch.u8(Op.Footer).u64(8L + 8L + 4L).u64(summaryStart).u64(summaryOffsetStart)
      crc.update(scratch.array, 0, scratch.length)
      scratch.u32(crc.getValue)
      emit(scratch.array, scratch.length)
      emit(Magic)
      out.flush()
    } finally out.close()
  }

  private def writeSchema(b: Buffer, s: Schema): Unit =
    b.record(Op.Schema) { r => r.u16(s.id).string(s.name).string(s.encoding).u32(s.data.length.toLong).raw(s.data) }

  private def writeChannel(b: Buffer, c: Channel): Unit =
    b.record(Op.Channel) { r => r.u16(c.id).u16(c.schemaId).string(c.topic).string(c.messageEncoding).map(c.metadata) }

  private def flushChunk(): Unit = if (chunk.length > 0) {
    val hasMessages = chunkStart != Long.MaxValue
    val start = written
    scratch.clear()
    scratch.u8(Op.Chunk).u64(8L + 8L + 8L + 4L + 4L + 8L + chunk.length)
    scratch.u64(if (hasMessages) chunkStart else 0L).u64(if (hasMessages) chunkEnd else 0L)
    scratch.u64(chunk.length.toLong).u32(Mcap.crc(chunk.array, 0, chunk.length)).string("").u64(chunk.length.toLong)
    emit(scratch.array, scratch.length)
    emit(chunk.array, chunk.length)
    val chunkLength = written - start
    val indexStart = written
    val indexOffsets = new Array[Long](indexedChannels.size)
    var i = 0
    while (i < indexedChannels.size) {
      val channelId = indexedChannels(i)
      val entries = chunkIndex(channelId)
      indexOffsets(i) = written
      scratch.clear()
      scratch.record(Op.MessageIndex) { r => r.u16(channelId).u32(entries.length.toLong).raw(entries.array, 0, entries.length) }
      emit(scratch.array, scratch.length)
      entries.clear()
      i += 1
    }
    chunkIndexes.record(Op.ChunkIndex) { r =>
      r.u64(if (hasMessages) chunkStart else 0L).u64(if (hasMessages) chunkEnd else 0L).u64(start).u64(chunkLength)
      val mapAt = r.length
      r.u32(0L)
      var j = 0
      while (j < indexOffsets.length) { r.u16(indexedChannels(j)).u64(indexOffsets(j)); j += 1 }
      r.setU32(mapAt, (r.length - mapAt - 4).toLong)
      r.u64(written - indexStart).string("").u64(chunk.length.toLong).u64(chunk.length.toLong)
    }
    chunkCount += 1
    chunk.clear()
    indexedChannels.clear()
    chunkStart = Long.MaxValue
    chunkEnd = Long.MinValue
  }

  private def emitRecord(op: Int)(body: Buffer => Unit): Unit = {
    scratch.clear()
    scratch.record(op)(body)
    emit(scratch.array, scratch.length)
  }

  private def emit(b: Array[Byte]): Unit = emit(b, b.length)

  private def emit(b: Array[Byte], n: Int): Unit = {
    out.write(b, 0, n)
    crc.update(b, 0, n)
    written += n
  }
}

/**
 * Reads MCAP files from start to end: the records of the data section, inside uncompressed chunks too, checking the
 * CRCs a file carries (chunks, data section, summary). Compressed chunks and other unknown content are refused with a
 * [[Mcap.FormatException]]; unknown record kinds are skipped, as the specification asks.
 */
object McapReader {
  import Mcap._

  /** What [[McapReader.stream]] meets in the data section, in file order. */
  sealed trait Item extends Product with Serializable

  /** A schema. */
  final case class SchemaItem(schema: Schema) extends Item

  /** A channel. */
  final case class ChannelItem(channel: Channel) extends Item

  /** A message. */
  final case class MessageItem(message: Message) extends Item

  /** The largest record this reader takes (a chunk of the gateway's writer is far smaller). */
  val MaxRecordBytes: Long = 256L * 1024 * 1024

  /** The whole file in `bytes`. */
  def read(bytes: Array[Byte]): Contents = {
    val in = new java.io.ByteArrayInputStream(bytes)
    val schemas = mutable.LinkedHashMap.empty[Int, Schema]
    val channels = mutable.LinkedHashMap.empty[Int, Channel]
    val messages = Vector.newBuilder[Message]
    val s = new Stream(in)
    s.items.foreach {
      case SchemaItem(x)  => schemas(x.id) = x
      case ChannelItem(x) => channels(x.id) = x
      case MessageItem(m) => messages += m
    }
    Contents(s.profile, s.library, schemas.toMap, channels.toMap, messages.result(), s.statistics)
  }

  /** Reads `in` lazily, one record at a time; the caller closes `in`. */
  def stream(in: InputStream): Stream = new Stream(in)

  /** One pass over a file: its header, then [[items]], then (once they are used up) its statistics. */
  final class Stream private[McapReader] (in: InputStream) {
    private val dataCrc = new CRC32
    private var summaryCrc: CRC32 = null
    private var pending = List.empty[Item]
    private var finished = false
    @volatile private var stats: Option[Statistics] = None
    private val head = new Array[Byte](9)

    private def readFully(b: Array[Byte], n: Int): Unit = {
      var at = 0
      while (at < n) {
        val got = in.read(b, at, n - at)
        if (got < 0) throw new EOFException(s"the file ends inside a record ($at of $n bytes)")
        at += got
      }
      dataCrcUpdate(b, n)
    }

    private def dataCrcUpdate(b: Array[Byte], n: Int): Unit =
      if (summaryCrc == null) dataCrc.update(b, 0, n) else summaryCrc.update(b, 0, n)

    /** One record: its opcode and content. */
    private def nextRecord(): (Int, Array[Byte]) = {
      readFully(head, 9)
      val op = head(0) & 0xff
      val length = new Fields(head, 1, 9).u64()
      if (length < 0 || length > MaxRecordBytes) throw new FormatException(s"record of opcode $op has length $length")
      val content = new Array[Byte](length.toInt)
      readFully(content, content.length)
      op -> content
    }

    private val (profileText, libraryText) = {
      val magic = new Array[Byte](8)
      readFully(magic, 8)
      if (!java.util.Arrays.equals(magic, Magic)) throw new FormatException("not an MCAP file (magic)")
      val (op, content) = nextRecord()
      if (op != Op.Header) throw new FormatException(s"the first record is opcode $op, not the Header")
      val f = new Fields(content, 0, content.length)
      (f.string(), f.string())
    }

    /** The Header's profile. */
    def profile: String = profileText

    /** The Header's library. */
    def library: String = libraryText

    /** The Statistics record, once the data section has been read to its end (if the file has one). */
    def statistics: Option[Statistics] = stats

    /** The schemas, channels and messages of the data section, in order. */
    val items: Iterator[Item] = new Iterator[Item] {
      def hasNext: Boolean = {
        while (pending.isEmpty && !finished) advance()
        pending.nonEmpty
      }
      def next(): Item = {
        if (!hasNext) throw new NoSuchElementException("no more records")
        val item = pending.head
        pending = pending.tail
        item
      }
    }

    private def advance(): Unit = {
      val crcBefore = dataCrc.getValue
      val (op, content) = nextRecord()
      pending = decode(op, content, crcBefore, inChunk = false)
    }

    private def decode(op: Int, content: Array[Byte], crcBefore: Long, inChunk: Boolean): List[Item] = {
      val f = new Fields(content, 0, content.length)
      op match {
        case Op.Schema =>
          val id = f.u16()
          val name = f.string()
          val encoding = f.string()
          val data = f.raw(f.lengthOf(f.u32()))
          if (id == 0) Nil else List(SchemaItem(Schema(id, name, encoding, data)))
        case Op.Channel =>
          List(ChannelItem(Channel(f.u16(), f.u16(), f.string(), f.string(), f.stringMap())))
        case Op.Message =>
          val channel = f.u16()
          val sequence = f.u32()
          val logTime = f.u64()
          val publishTime = f.u64()
          List(MessageItem(Message(channel, sequence, logTime, publishTime, f.rest())))
        case Op.Chunk if !inChunk =>
          f.u64(); f.u64()
          val uncompressedSize = f.u64()
          val uncompressedCrc = f.u32()
          val compression = f.string()
          val size = f.lengthOf(f.u64())
          if (compression.nonEmpty) throw new FormatException(s"chunk compressed with $compression: not supported")
          if (size.toLong != uncompressedSize) throw new FormatException("chunk sizes disagree")
          val from = f.position
          if (uncompressedCrc != 0 && Mcap.crc(content, from, size) != uncompressedCrc) throw new FormatException("chunk CRC mismatch")
          val items = List.newBuilder[Item]
          val inner = new Fields(content, from, from + size)
          while (inner.remaining > 0) {
            val innerOp = inner.u8()
            val n = inner.lengthOf(inner.u64())
            val start = inner.position
            inner.raw(n)
            items ++= decode(innerOp, java.util.Arrays.copyOfRange(content, start, start + n), 0L, inChunk = true)
          }
          items.result()
        case Op.DataEnd if !inChunk =>
          val expected = f.u32()
          if (expected != 0 && expected != crcBefore) throw new FormatException("data section CRC mismatch")
          summaryCrc = new CRC32
          readSummary()
          finished = true
          Nil
        case Op.Footer =>
          // A file without Data End: the footer ends it.
          finished = true
          Nil
        case _ => Nil // message indexes, attachments, metadata, application records: not needed here
      }
    }

    private def readSummary(): Unit = {
      var done = false
      while (!done) {
        readFully(head, 9)
        val op = head(0) & 0xff
        val length = new Fields(head, 1, 9).u64()
        if (op == Op.Footer) {
          if (length != 20) throw new FormatException(s"footer of $length bytes")
          val body = new Array[Byte](16)
          readFully(body, 16)
          val expected = new Array[Byte](4)
          val sum = summaryCrc.getValue
          var at = 0
          while (at < 4) { val got = in.read(expected, at, 4 - at); if (got < 0) throw new EOFException("footer"); at += got }
          val crcField = new Fields(expected, 0, 4).u32()
          if (crcField != 0 && crcField != sum) throw new FormatException("summary CRC mismatch")
          val magic = new Array[Byte](8)
          at = 0
          while (at < 8) { val got = in.read(magic, at, 8 - at); if (got < 0) throw new EOFException("closing magic"); at += got }
          if (!java.util.Arrays.equals(magic, Magic)) throw new FormatException("the file does not end with the magic")
          done = true
        } else {
          if (length < 0 || length > MaxRecordBytes) throw new FormatException(s"summary record of opcode $op has length $length")
          val content = new Array[Byte](length.toInt)
          readFully(content, content.length)
          if (op == Op.Statistics) {
            val f = new Fields(content, 0, content.length)
            val count = f.u64()
            val schemaCount = f.u16()
            val channelCount = f.u32().toInt
            f.u32(); f.u32()
            val chunkCount = f.u32().toInt
            stats = Some(Statistics(count, schemaCount, channelCount, chunkCount, f.u64(), f.u64(), f.countMap()))
          }
        }
      }
    }
  }
}
