package naogateway.gateway.recording

import java.io.{EOFException, InputStream}
import java.util.zip.CRC32

import scala.collection.mutable

/** Reads MCAP files from start to end: the records of the data section, inside uncompressed chunks too, checking the
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
          if (uncompressedCrc != 0 && Mcap.crc(content, from, size) != uncompressedCrc)
            throw new FormatException("chunk CRC mismatch")
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
          while (at < 4) {
            val got = in.read(expected, at, 4 - at); if (got < 0) throw new EOFException("footer"); at += got
          }
          val crcField = new Fields(expected, 0, 4).u32()
          if (crcField != 0 && crcField != sum) throw new FormatException("summary CRC mismatch")
          val magic = new Array[Byte](8)
          at = 0
          while (at < 8) {
            val got = in.read(magic, at, 8 - at); if (got < 0) throw new EOFException("closing magic"); at += got
          }
          if (!java.util.Arrays.equals(magic, Magic)) throw new FormatException("the file does not end with the magic")
          done = true
        } else {
          if (length < 0 || length > MaxRecordBytes)
            throw new FormatException(s"summary record of opcode $op has length $length")
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
