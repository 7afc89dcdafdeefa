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

  // SPEC §3: robot 1, team 1, activeAgent "AgentTest", as the CM-530 sends it (legacy header).
  private val workedHeader = hex("00 2A 00 00 00 00 00 00 00 00 00 12")
  private val workedProtobuf = hex("08 01 BA 01 0D 10 01 62 09 41 67 65 6E 74 54 65 73 74")
  private val workedFrame = workedHeader ++ workedProtobuf
  private val workedContents =
    MessageContents(robotId = 1, status = Some(Status(teamID = Some(1), activeAgent = Some("AgentTest"))))

  "The SPEC §3 worked example" should {
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

  "MessageContents.parse" should {
    "agree with the general ScalaPB path for every message" in {
      forAll(contents) { c =>
        val bytes = c.toMessage.toByteArray
        MessageContents.parse(bytes) shouldBe MessageContents.of(Message.parseFrom(bytes))
        MessageContents.parse(bytes) shouldBe Right(c)
      }
    }
    "merge an extension that occurs twice, as protobuf does" in {
      val first = Message(robotID = 4).withExtension(naogateway.proto.MessageProto.status)(Some(Status(teamID = Some(3))))
      val second = Message(robotID = 4).withExtension(naogateway.proto.MessageProto.status)(
        Some(Status(activeRole = Some("striker")))
      )
      val merged = MessageContents.parse(first.toByteArray ++ second.toByteArray)
      merged.map(_.status) shouldBe Right(Some(Status(teamID = Some(3), activeRole = Some("striker"))))
    }
    "refuse group wire types, as the general path does" in {
      // robotID 4, then field 11 with wire type 4 (end group) and no group open.
      MessageContents.parse(Array[Byte](0x08, 0x04, 0x5c)) should matchPattern { case Left(FrameError.BadProtobuf(_)) => }
      // robotID 1, then an empty group in field 5.
      MessageContents.parse(Array[Byte](0x08, 0x01, 0x2b, 0x2c)) should matchPattern { case Left(FrameError.BadProtobuf(_)) => }
    }
    "agree with the general path on arbitrary bytes after a valid robot id" in {
      forAll(anyBytes) { tail =>
        val bytes = Array[Byte](0x08, 0x01) ++ tail.take(60)
        val general =
          try MessageContents.of(Message.parseFrom(bytes)).isRight
          catch { case _: Exception => false }
        MessageContents.parse(bytes).isRight shouldBe general
      }
    }
    "agree with the general path on arbitrary bytes" in {
      forAll(anyBytes) { bytes =>
        val general =
          try MessageContents.of(Message.parseFrom(bytes)).isRight
          catch { case _: Exception => false }
        MessageContents.parse(bytes).isRight shouldBe general
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
