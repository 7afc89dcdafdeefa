package naogateway.gateway.recording

import java.io.OutputStream
import java.util.zip.CRC32

import scala.collection.mutable

/** Writes one MCAP file to `out`, which it owns and closes. Messages are gathered into uncompressed chunks of about
  * `chunkBytes`, each followed by its message indexes, so readers can seek by time; [[close]] writes the summary and
  * the footer. Not thread-safe: one writer thread.
  *
  * @param profile
  *   the Header's profile ("" for none)
  * @param library
  *   the Header's library text: who wrote the file
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
  def addChannel(
      topic: String, messageEncoding: String, schemaId: Int, metadata: Map[String, String] = Map.empty): Int = {
    require(schemaId == 0 || schemas.contains(schemaId), s"no schema $schemaId")
    require(channels.size < 65535, "an MCAP file holds at most 65535 channels")
    val c = Channel(channels.size + 1, schemaId, topic, messageEncoding, metadata)
    channels(c.id) = c
    writeChannel(chunk, c)
    c.id
  }

  /** Writes one message on `channelId`; `data` is copied. */
  def write(channelId: Int, logTime: Long, publishTime: Long, data: Array[Byte]): Unit =
    write(channelId, logTime, publishTime, data, 0, data.length)

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

  /** Ends the chunk being filled (if it holds anything) and flushes `out`: what was written so far is on its way to
    * disk.
    */
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
      group(Op.Schema)(
        schemas.values.foreach(s => { scratch.clear(); writeSchema(scratch, s); emit(scratch.array, scratch.length) }))
      group(Op.Channel)(
        channels.values.foreach(c => {
          scratch.clear(); writeChannel(scratch, c); emit(scratch.array, scratch.length)
        }))
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
      offsets.result().foreach { case (op, start, length) =>
        emitRecord(Op.SummaryOffset)(_.u8(op).u64(start).u64(length))
      }
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
      scratch.record(Op.MessageIndex) { r =>
        r.u16(channelId).u32(entries.length.toLong).raw(entries.array, 0, entries.length)
      }
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
