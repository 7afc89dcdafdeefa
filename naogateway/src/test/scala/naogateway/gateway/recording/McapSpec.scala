package naogateway.gateway.recording

import java.io.ByteArrayOutputStream
import java.nio.charset.StandardCharsets

import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.proto.Status

class McapSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {

  private final case class Written(topics: Vector[(String, String)], messages: Vector[(Int, Long, Long, Vector[Byte])])

  private val written: Gen[Written] = for {
    channels <- Gen.choose(1, 6)
    topics <- Gen.listOfN(channels, Gen.zip(Gen.alphaStr.map("/" + _), Gen.oneOf("protobuf", "json", "")))
    count <- Gen.choose(0, 400)
    messages <- Gen.listOfN(
      count,
      for {
        channel <- Gen.choose(1, channels)
        time <- Gen.choose(0L, Long.MaxValue / 2)
        published <- Gen.choose(0L, Long.MaxValue / 2)
        data <- Gen.containerOf[Vector, Byte](Gen.choose(Byte.MinValue, Byte.MaxValue))
      } yield (channel, time, published, data)
    )
  } yield Written(topics.toVector, messages.toVector)

  // Some channels without metadata: an empty map is a length of 0 and nothing else.
  private def metadata(i: Int): Map[String, String] =
    if (i % 3 == 0) Map.empty else Map("index" -> i.toString, "k" -> "v")

  private def write(w: Written, chunkBytes: Int): Array[Byte] = {
    val out = new ByteArrayOutputStream()
    val writer = new McapWriter(out, "x-test", "McapSpec", chunkBytes)
    val schema = writer.addSchema("test.Thing", "protobuf", Array[Byte](1, 2, 3))
    w.topics.zipWithIndex.foreach { case ((topic, encoding), i) =>
      writer.addChannel(topic, encoding, if (i % 2 == 0) schema else 0, metadata(i)) shouldBe i + 1
    }
    w.messages.foreach { case (c, t, p, d) => writer.write(c, t, p, d.toArray) }
    writer.close()
    out.toByteArray
  }

  "The MCAP writer and reader" must {
    "give back every schema, channel and message, in order, whatever the chunk size" in {
      forAll(written, Gen.oneOf(1024, 4096, 1 << 20)) { (w, chunkBytes) =>
        val bytes = write(w, chunkBytes)
        val read = McapReader.read(bytes)
        read.profile shouldBe "x-test"
        read.library shouldBe "McapSpec"
        read.schemas.values.toVector.map(s => (s.id, s.name, s.encoding, s.data.toVector)) shouldBe
          Vector((1, "test.Thing", "protobuf", Vector[Byte](1, 2, 3)))
        read.channels.toVector.sortBy(_._1).map { case (id, c) =>
          (id, c.topic, c.messageEncoding, c.schemaId, c.metadata)
        } shouldBe
          w.topics.zipWithIndex.map { case ((t, e), i) => (i + 1, t, e, if (i % 2 == 0) 1 else 0, metadata(i)) }
        read.messages.map(m => (m.channelId, m.logTime, m.publishTime, m.data.toVector)) shouldBe w.messages
        // Sequence numbers count per channel from 1.
        read.messages.groupBy(_.channelId).values.foreach(ms =>
          ms.map(_.sequence) shouldBe (1L to ms.size.toLong).toVector)
        val stats = read.statistics.getOrElse(fail("no statistics"))
        stats.messageCount shouldBe w.messages.size.toLong
        stats.channelCount shouldBe w.topics.size
        stats.schemaCount shouldBe 1
        stats.channelMessageCounts shouldBe w.messages.groupBy(_._1).map { case (c, ms) => c -> ms.size.toLong }
        if (w.messages.nonEmpty) {
          stats.messageStartTime shouldBe w.messages.map(_._2).min
          stats.messageEndTime shouldBe w.messages.map(_._2).max
        }
      }
    }

    "begin and end with the magic and put the footer's offsets where the summary and its offsets are" in {
      val bytes = write(Written(Vector("/a" -> "json"), Vector((1, 5L, 5L, Vector[Byte](42)))), 1024)
      bytes.take(8).toVector shouldBe Mcap.Magic.toVector
      bytes.takeRight(8).toVector shouldBe Mcap.Magic.toVector
      val footer = new Mcap.Fields(bytes, bytes.length - 8 - 20, bytes.length - 8)
      val summaryStart = footer.u64().toInt
      val summaryOffsetStart = footer.u64().toInt
      bytes(bytes.length - 8 - 20 - 9) shouldBe Mcap.Op.Footer.toByte
      bytes(summaryStart) shouldBe Mcap.Op.Schema.toByte
      bytes(summaryOffsetStart) shouldBe Mcap.Op.SummaryOffset.toByte
      // The record before the summary is Data End (opcode, u64 length 4, u32 CRC).
      bytes(summaryStart - 13) shouldBe Mcap.Op.DataEnd.toByte
    }

    "refuse a file whose bytes changed (CRCs) and one that is not MCAP" in {
      val w = Written(Vector("/a" -> "json"),
        (1 to 50).toVector.map(i => (1, i.toLong, i.toLong, s"message $i".getBytes(StandardCharsets.UTF_8).toVector)))
      val bytes = write(w, 1024)
      // A byte inside a message of the first chunk, and a byte of the summary.
      val inChunk = bytes.indexOfSlice("message 3".getBytes(StandardCharsets.UTF_8).toSeq)
      val corrupt = bytes.clone()
      corrupt(inChunk + 8) = 'X'.toByte
      an[Mcap.FormatException] should be thrownBy McapReader.read(corrupt)
      val summary = bytes.clone()
      summary(bytes.length - 8 - 29 - 5) = (summary(bytes.length - 8 - 29 - 5) ^ 1).toByte
      an[Mcap.FormatException] should be thrownBy McapReader.read(summary)
      an[Mcap.FormatException] should be thrownBy McapReader.read(
        "not an mcap file at all".getBytes(StandardCharsets.UTF_8))
    }

    "leave what was flushed readable in a file that was never closed (a crash)" in {
      val out = new ByteArrayOutputStream()
      val writer = new McapWriter(out, "", "McapSpec")
      val channel = writer.addChannel("/a", "json", 0)
      (1 to 3).foreach(i => writer.write(channel, i.toLong, i.toLong, Array(i.toByte)))
      writer.flush()
      writer.write(channel, 4L, 4L, Array(4.toByte)) // still in the chunk being filled when the "crash" comes
      val stream = McapReader.stream(new java.io.ByteArrayInputStream(out.toByteArray))
      val got = Vector.newBuilder[Long]
      an[java.io.EOFException] should be thrownBy stream.items.foreach {
        case McapReader.MessageItem(m) => got += m.logTime
        case _                         => ()
      }
      got.result() shouldBe Vector(1L, 2L, 3L)
    }

    "carry the project's protobuf descriptors, so a Status can be decoded from the file alone" in {
      val set = com.google.protobuf.DescriptorProtos.FileDescriptorSet.parseFrom(Recording.descriptorSet)
      val files = set.getFileList
      val byName = scala.collection.mutable.Map.empty[String, com.google.protobuf.Descriptors.FileDescriptor]
      files.forEach { f =>
        val deps = f.getDependencyList.toArray.map(d => byName(d.toString))
        byName(f.getName) = com.google.protobuf.Descriptors.FileDescriptor.buildFrom(f, deps)
      }
      val status = byName("naogateway/proto/message.proto").findMessageTypeByName("Status")
      val decoded = com.google.protobuf.DynamicMessage.parseFrom(status,
        Status(timestamp = Some(1234L), activeAgent = Some("keeper")).toByteArray)
      decoded.getField(status.findFieldByName("timestamp")) shouldBe 1234L
      decoded.getField(status.findFieldByName("activeAgent")) shouldBe "keeper"
      byName.keySet should contain("naogateway/proto/recording.proto")
    }
  }
}
