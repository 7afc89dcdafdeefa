package naogateway.wire

import org.scalacheck.{Arbitrary, Gen}
import org.scalatest.EitherValues
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.proto.{Message, Status}

class FumanoidsFrameSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks with EitherValues {
  import MessageGenerators._

  implicit override val generatorDrivenConfig: PropertyCheckConfiguration =
    PropertyCheckConfiguration(minSuccessful = 300)

  private def hex(s: String): Array[Byte] = s.split(' ').map(Integer.parseInt(_, 16).toByte)

  // docs/protocol.md 9.1: robot 1, team 1, activeAgent "AgentTest", as the CM-530 sends it (legacy header).
  private val workedHeader = hex("00 2A 00 00 00 00 00 00 00 00 00 12")
  private val workedProtobuf = hex("08 01 BA 01 0D 10 01 62 09 41 67 65 6E 74 54 65 73 74")
  private val workedFrame = workedHeader ++ workedProtobuf
  private val workedContents =
    MessageContents(robotId = 1, status = Some(Status(teamID = Some(1), activeAgent = Some("AgentTest"))))

  "The docs/protocol.md 9.1 worked example" should {
    "encode byte for byte" in {
      MessageContents.encodeFrame(workedContents).map(_.toSeq) shouldBe Right(workedFrame.toSeq)
    }
    "decode to robot 1, team 1, agent AgentTest" in {
      val (header, contents) = MessageContents.decodeFrame(workedFrame).value
      header shouldBe FrameHeader(HeaderForm.Legacy, gzip = false, payloadLength = 18)
      contents shouldBe workedContents
    }
    "decode in the 2014 form with the same protobuf bytes" in {
      val compact = hex("00 2A 00 00 00 00 00 12") ++ workedProtobuf
      MessageContents.encodeFrame(workedContents, HeaderForm.Compact).map(_.toSeq) shouldBe Right(compact.toSeq)
      MessageContents.decodeFrame(compact).map(_._2) shouldBe Right(workedContents)
    }
  }

  "FumanoidsFrame.decode" should {
    "understand gzip-flagged payloads" in {
      val framed = MessageContents.encodeFrame(workedContents, gzip = true).toOption.get
      framed(2) shouldBe FumanoidsFrame.GzipFlag.toByte
      val (header, contents) = MessageContents.decodeFrame(framed).value
      header.gzip shouldBe true
      contents shouldBe workedContents
    }
    "refuse a gzip payload of two members, or with bytes after its member: one member only (protocol.md §4.3)" in {
      def gzip(bytes: Array[Byte]): Array[Byte] = {
        val out = new java.io.ByteArrayOutputStream()
        val z = new java.util.zip.GZIPOutputStream(out)
        z.write(bytes); z.close()
        out.toByteArray
      }
      def gzipFrame(payload: Array[Byte]): Array[Byte] =
        java.nio.ByteBuffer.allocate(12 + payload.length).putInt(0x002a0200).putInt(0).putInt(payload.length).put(
          payload).array()
      val half = workedProtobuf.length / 2
      val single = gzipFrame(gzip(workedProtobuf))
      MessageContents.decodeFrame(single).map(_._2) shouldBe Right(workedContents)
      // The two halves of the Message in two members: a concatenating reader would see the whole Message.
      val twoMembers = gzipFrame(gzip(workedProtobuf.take(half)) ++ gzip(workedProtobuf.drop(half)))
      MessageContents.decodeFrame(twoMembers) should matchPattern {
        case Left(FrameError.BadGzip(r)) if r.contains("after the gzip member") =>
      }
      FumanoidsFrame.decode(twoMembers) should matchPattern { case Left(FrameError.BadGzip(_)) => }
      val trailing = gzipFrame(gzip(workedProtobuf) ++ Array[Byte](0x00, 0x13, 0x37))
      MessageContents.decodeFrame(trailing) shouldBe Left(FrameError.BadGzip("3 bytes after the gzip member"))
      // A member cut short, or with a wrong CRC, is refused as well.
      val member = gzip(workedProtobuf)
      MessageContents.decodeFrame(gzipFrame(member.dropRight(1))) should matchPattern {
        case Left(FrameError.BadGzip(_)) =>
      }
      val badCrc = member.clone(); badCrc(member.length - 8) = (badCrc(member.length - 8) ^ 1).toByte
      MessageContents.decodeFrame(gzipFrame(badCrc)) shouldBe Left(FrameError.BadGzip("CRC-32 mismatch"))
    }
    "read a gzip member whose header carries a file name and a comment" in {
      val plain = new java.io.ByteArrayOutputStream()
      val z = new java.util.zip.GZIPOutputStream(plain)
      z.write(workedProtobuf); z.close()
      val member = plain.toByteArray
      // FLG = FNAME | FCOMMENT, then "a\0" and "b\0" after the 10-byte header.
      val named =
        member.take(3) ++ Array[Byte](0x18) ++ member.slice(4, 10) ++ Array[Byte](0x61, 0, 0x62, 0) ++ member.drop(10)
      val frame = java.nio.ByteBuffer.allocate(12 + named.length).putInt(0x002a0200).putInt(0).putInt(named.length).put(
        named).array()
      MessageContents.decodeFrame(frame).map(_._2) shouldBe Right(workedContents)
    }
    "refuse a truncated header" in {
      FumanoidsFrame.decode(workedFrame.take(5)) shouldBe Left(FrameError.Truncated(8, 5))
      FumanoidsFrame.decode(workedFrame.take(10)) shouldBe Left(FrameError.Truncated(12, 10))
    }
    "refuse a wrong operation" in {
      val wrong = workedFrame.clone(); wrong(1) = 43
      FumanoidsFrame.decode(wrong) shouldBe Left(FrameError.WrongOperation(43, 0))
    }
    "refuse unknown flags" in {
      val wrong = workedFrame.clone(); wrong(2) = 1
      FumanoidsFrame.decode(wrong) shouldBe Left(FrameError.UnsupportedFlags(1))
    }
    "refuse a length that disagrees with the datagram" in {
      FumanoidsFrame.decode(workedFrame.dropRight(1)) shouldBe Left(FrameError.LengthMismatch(18, 17))
      FumanoidsFrame.decode(workedFrame :+ 0.toByte) shouldBe Left(FrameError.LengthMismatch(18, 19))
    }
    "refuse a gzip flag on a payload that is not gzip" in {
      val wrong = workedFrame.clone(); wrong(2) = 2
      FumanoidsFrame.decode(wrong) should matchPattern { case Left(FrameError.BadGzip(_)) => }
    }
    "refuse a payload that is not a Message" in {
      // robotID is required: an empty Message is refused, and so is a truncated field.
      val noRobotId = hex("00 2A 00 00 00 00 00 02 10 01")
      FumanoidsFrame.decode(noRobotId) should matchPattern { case Left(FrameError.BadProtobuf(_)) => }
      val cut = hex("00 2A 00 00 00 00 00 03 08 01 BA")
      FumanoidsFrame.decode(cut) should matchPattern { case Left(FrameError.BadProtobuf(_)) => }
    }
    "refuse datagrams over 1400 bytes" in {
      FumanoidsFrame.decode(new Array[Byte](1401)) shouldBe Left(FrameError.Oversize(1401, 1400))
    }
    "report a malformed known extension as a typed error" in {
      // Field 23 (Status) whose bytes are a truncated varint.
      val badStatus = hex("00 2A 00 00 00 00 00 06 08 01 BA 01 01 10")
      MessageContents.decodeFrame(badStatus) should matchPattern { case Left(FrameError.BadProtobuf(_)) => }
    }
    "list extensions it does not know and keep the known ones" in {
      // robot 3, extension 50 (varint 7), then the Status of the worked example.
      val bytes = hex("08 03 90 03 07 BA 01 0D 10 01 62 09 41 67 65 6E 74 54 65 73 74")
      val framed = FumanoidsFrame.encodeProtobuf(bytes).toOption.get
      val contents = MessageContents.decodeFrame(framed).value._2
      contents.unknownExtensions shouldBe Vector(50)
      contents.status shouldBe workedContents.status
    }
  }

  "FumanoidsFrame.encode" should {
    "refuse a frame over 1400 bytes with a clear error" in {
      val big = Message(robotID = 1).withExtension(naogateway.proto.MessageProto.status)(
        Some(Status(activeAgent = Some("x" * 1400)))
      )
      val error = FumanoidsFrame.encode(big).left.value
      error.size should be > 1400
      error.describe should include("1400")
    }
    "accept exactly 1400 bytes" in {
      val protobuf = Message(robotID = 1).toByteArray ++ Array.fill(1388 - 2)(0.toByte)
      FumanoidsFrame.encodeProtobuf(protobuf).map(_.length) shouldBe Right(1400)
      FumanoidsFrame.encodeProtobuf(protobuf :+ 0.toByte).isLeft shouldBe true
    }
  }

  "Frames" should {
    "round-trip every message kind in both header forms, with and without gzip" in {
      forAll(contents, headerForm, Arbitrary.arbitrary[Boolean]) { (c, form, gzip) =>
        MessageContents.encodeFrame(c, form, gzip) match {
          case Right(bytes) =>
            bytes.length should be <= WireLimits.MaxDatagramBytes
            MessageContents.decodeFrame(bytes) shouldBe Right(
              FrameHeader(form, gzip, bytes.length - form.headerBytes) -> c
            )
          case Left(oversize) => oversize.size should be > WireLimits.MaxDatagramBytes
        }
      }
    }
    "never throw on arbitrary bytes" in {
      forAll(anyBytes) { bytes =>
        noException should be thrownBy MessageContents.decodeFrame(bytes)
      }
    }
    "never throw on arbitrary bytes behind a valid-looking header" in {
      val tails = Gen.choose(0, 300).flatMap(n => Gen.listOfN(n, Arbitrary.arbitrary[Byte])).map(_.toArray)
      forAll(tails, headerForm, Arbitrary.arbitrary[Boolean]) { (tail, form, gzip) =>
        val framed = FumanoidsFrame.encodeProtobuf(tail, form).toOption.get
        if (gzip) framed(2) = 2
        noException should be thrownBy MessageContents.decodeFrame(framed)
      }
    }
  }
}

class MessageContentsSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {
  import MessageGenerators._

  implicit override val generatorDrivenConfig: PropertyCheckConfiguration =
    PropertyCheckConfiguration(minSuccessful = 2000)

  /** The general path: the gateway's `Message` parse (ScalaPB after the §5 rules), then the contents. */
  private def general(bytes: Array[Byte]): Either[FrameError, MessageContents] =
    FumanoidsFrame.parseMessage(bytes).flatMap(MessageContents.of)

  /** Both paths' answer when they agree; the test fails when they do not. */
  private def both(bytes: Array[Byte]): Either[FrameError, MessageContents] = {
    val fast = MessageContents.parse(bytes)
    fast.isRight shouldBe general(bytes).isRight
    fast.foreach(c => general(bytes) shouldBe Right(c))
    fast
  }

  "MessageContents.parse" should {
    "agree with the general ScalaPB path for every message" in {
      forAll(contents) { c =>
        val bytes = c.toMessage.toByteArray
        MessageContents.parse(bytes) shouldBe general(bytes)
        MessageContents.parse(bytes) shouldBe MessageContents.of(Message.parseFrom(bytes))
        MessageContents.parse(bytes) shouldBe Right(c)
      }
    }
    "merge an extension that occurs twice, as protobuf does" in {
      val first =
        Message(robotID = 4).withExtension(naogateway.proto.MessageProto.status)(Some(Status(teamID = Some(3))))
      val second = Message(robotID = 4).withExtension(naogateway.proto.MessageProto.status)(
        Some(Status(activeRole = Some("striker")))
      )
      val merged = MessageContents.parse(first.toByteArray ++ second.toByteArray)
      merged.map(_.status) shouldBe Right(Some(Status(teamID = Some(3), activeRole = Some("striker"))))
    }
    "skip unknown groups like every other unknown field, in both paths (protocol.md §5)" in {
      def bytes(s: String) = s.split(' ').map(Integer.parseInt(_, 16).toByte)
      // robotID 1, then an empty group in field 5.
      both(bytes("08 01 2B 2C")) shouldBe Right(MessageContents(1))
      // robotID 1, a group in field 50 holding a varint and an inner group, then Status with teamID 1.
      both(bytes("08 01 93 03 08 05 5B 5C 94 03 BA 01 02 10 01")) shouldBe
        Right(MessageContents(1, status = Some(Status(teamID = Some(1)))))
      // A group inside a known extension: Status with teamID 1 and an unknown group in field 11.
      both(bytes("08 01 BA 01 04 10 01 5B 5C")) shouldBe Right(MessageContents(1,
          status = Some(Status(teamID = Some(1)))))
    }
    "still refuse malformed groups: an end without a start, or an end of another field" in {
      both(Array[Byte](0x08, 0x04, 0x5c)) should matchPattern { case Left(FrameError.BadProtobuf(_)) => }
      both(Array[Byte](0x08, 0x01, 0x2b, 0x34)) should matchPattern { case Left(FrameError.BadProtobuf(_)) => }
      both(Array[Byte](0x08, 0x01, 0x2b)) should matchPattern { case Left(FrameError.BadProtobuf(_)) => }
    }
    "read a display string that is not UTF-8 with U+FFFD, keeping the rest of the message (protocol.md §5)" in {
      // Status: teamID 1, activeAgent = 41 FF 42 ("A", a byte no UTF-8 text holds, "B").
      val bad = Array[Byte](0x08, 0x01, 0xba.toByte, 0x01, 0x07, 0x10, 0x01, 0x62, 0x03, 0x41, 0xff.toByte, 0x42)
      both(bad) shouldBe Right(MessageContents(1,
          status = Some(Status(teamID = Some(1), activeAgent = Some("A\uFFFDB")))))
      // Valid text beyond ASCII is kept as it is; a sequence cut short is replaced like any malformed one.
      val text = "Müller ✓ 😀"
      val valid = Status(activeAgent = Some(text)).toByteArray
      both(Array[Byte](0x08, 0x01, 0xba.toByte, 0x01, valid.length.toByte) ++ valid).map(
        _.status.flatMap(_.activeAgent)) shouldBe
        Right(Some(text))
      val cut = Array[Byte](0x62, 0x02, 0x41, 0xc3.toByte)
      both(Array[Byte](0x08, 0x01, 0xba.toByte, 0x01, cut.length.toByte) ++ cut).map(
        _.status.flatMap(_.activeAgent)) shouldBe
        Right(Some("A\uFFFD"))
    }
    "refuse a varint that does not fit its 32-bit field instead of cutting it (protocol.md §5)" in {
      // robotID 2^32 + 5: cut to 32 bits it would read as robot 5.
      both(Array[Byte](0x08, 0x85.toByte, 0x80.toByte, 0x80.toByte, 0x80.toByte, 0x10)) should matchPattern {
        case Left(FrameError.BadProtobuf(reason)) if reason.contains("4294967301") =>
      }
      // robotID 2^31: positive, but beyond int32.
      both(Array[Byte](0x08, 0x80.toByte, 0x80.toByte, 0x80.toByte, 0x80.toByte, 0x08)) should matchPattern {
        case Left(FrameError.BadProtobuf(_)) =>
      }
      // Status.teamID (uint32) 2^32 + 1.
      both(Array[Byte](0x08, 0x01, 0xba.toByte, 0x01, 0x06, 0x10, 0x81.toByte, 0x80.toByte, 0x80.toByte, 0x80.toByte,
          0x10)) should
        matchPattern { case Left(FrameError.BadProtobuf(_)) => }
      // −1 in its 10-byte form and the largest uint32 are in range.
      both(Array[Byte](0x08) ++ Array.fill(9)(0xff.toByte) :+ 0x01.toByte) shouldBe Right(MessageContents(-1))
      both(Array[Byte](0x08, 0x01, 0xba.toByte, 0x01, 0x06, 0x10, 0xff.toByte, 0xff.toByte, 0xff.toByte, 0xff.toByte,
          0x0f)) shouldBe
        Right(MessageContents(1, status = Some(Status(teamID = Some(0xffffffff)))))
    }
    "agree with the general path on arbitrary bytes after a valid robot id" in {
      forAll(anyBytes) { tail =>
        val bytes = Array[Byte](0x08, 0x01) ++ tail.take(60)
        both(bytes)
      }
    }
    "agree with the general path on arbitrary bytes" in {
      forAll(anyBytes) { bytes =>
        both(bytes)
      }
    }
  }
}

class MessageContentsEncodingSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {
  import MessageGenerators._

  "MessageContents.toProtobuf" should {
    "write a Message equal to ScalaPB's for every message, fields in ascending order" in {
      forAll(contents) { c =>
        val bytes = c.toProtobuf
        Message.parseFrom(bytes) shouldBe c.toMessage
        val fields = Iterator
          .unfold(com.google.protobuf.CodedInputStream.newInstance(bytes)) { in =>
            val tag = in.readTag()
            if (tag == 0) None else { in.skipField(tag); Some((tag >>> 3, in)) }
          }
          .toVector
        fields shouldBe fields.sorted
      }
    }
  }
}
