package naogateway.sim.gs1500m

import scala.collection.immutable.ArraySeq

import org.scalacheck.{Arbitrary, Gen}
import org.scalatest.EitherValues
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.sim.gs1500m.SerialEvent._

class Gs1500mSerialSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks with EitherValues {

  implicit override val generatorDrivenConfig: PropertyCheckConfiguration =
    PropertyCheckConfiguration(minSuccessful = 300)

  private def hex(s: String): ArraySeq[Byte] =
    ArraySeq.unsafeWrapArray(s.split(' ').map(Integer.parseInt(_, 16).toByte))
  private def ascii(s: String): ArraySeq[Byte] = ArraySeq.unsafeWrapArray(s.getBytes("ISO-8859-1"))
  private val Esc = "\u001b"

  private def decodeChunked(bytes: ArraySeq[Byte], sizes: List[Int]): (SerialDecoder, Vector[SerialEvent]) = {
    var decoder = SerialDecoder.empty
    val out = Vector.newBuilder[SerialEvent]
    var rest = bytes
    var cuts = sizes
    while (rest.nonEmpty) {
      val n = cuts match {
        case h :: t => cuts = t; math.max(1, h)
        case Nil    => rest.length
      }
      val (chunk, tail) = rest.splitAt(n)
      val (next, events) = decoder.feed(chunk)
      decoder = next
      out ++= events
      rest = tail
    }
    (decoder, out.result())
  }

  // docs/protocol.md 9.1: the thesis's worked example as the CM-530 hands it to the module.
  private val serialPrefix = hex("1B 5A 30 30 30 33 30")
  private val fumanoidsFrame =
    hex("00 2A 00 00 00 00 00 00 00 00 00 12") ++ hex("08 01 BA 01 0D 10 01 62 09 41 67 65 6E 74 54 65 73 74")

  "The thesis's serial example" should {
    "give the prefix 1B 5A 30 30 30 33 30 for 30 bytes on connection 0" in {
      Gs1500mSerial.bulkHeader(0, 30).value shouldBe serialPrefix
    }
    "encode the whole worked example byte for byte" in {
      fumanoidsFrame.length shouldBe 30
      Gs1500mSerial.encodeBulk(0, fumanoidsFrame).value shouldBe serialPrefix ++ fumanoidsFrame
      Gs1500mSerial.encode(Data(0, None, fumanoidsFrame)).value shouldBe serialPrefix ++ fumanoidsFrame
    }
    "decode back to the datagram" in {
      SerialDecoder.empty.feed(serialPrefix ++ fumanoidsFrame)._2 shouldBe Vector(Data(0, None, fumanoidsFrame))
    }
  }

  "The encoder" should {
    "name connections by one lower-case hex digit" in {
      Gs1500mSerial.bulkHeader(10, 5).value shouldBe ascii(s"${Esc}Za0005")
      Gs1500mSerial.bulkHeader(15, 1400).value shouldBe ascii(s"${Esc}Zf1400")
    }
    "refuse connection numbers beyond 16 connections and data beyond 1400 bytes" in {
      Gs1500mSerial.bulkHeader(16, 1).left.value shouldBe SerialError.BadCid(16)
      Gs1500mSerial.bulkHeader(-1, 1).left.value shouldBe SerialError.BadCid(-1)
      Gs1500mSerial.bulkHeader(0, 1401).left.value shouldBe SerialError.TooLong(1401, 1400)
    }
    "frame a UDP server datagram as ESC y cid ip SPACE port TAB len4 data" in {
      val item = Data(3, Some(Remote("192.168.1.100", 3838)), ascii("hello"))
      Gs1500mSerial.encode(item).value shouldBe ascii(s"${Esc}y3192.168.1.100 3838\t0005hello")
    }
    "refuse senders that are not dotted IPv4 with a valid port" in {
      for (remote <- Seq(Remote("192.168.1", 1), Remote("192.168.1.256", 1), Remote("a.b.c.d", 1),
          Remote("10.0.0.01", 1), Remote("10.0.0.1", 65536)))
        Gs1500mSerial.udpServerHeader(0, remote, 1).left.value shouldBe SerialError.BadRemote(remote)
    }
    "write replies and status lines" in {
      Gs1500mSerial.encode(Ack).value shouldBe ascii(s"${Esc}O")
      Gs1500mSerial.encode(Fail).value shouldBe ascii(s"${Esc}F")
      Gs1500mSerial.encode(StatusLine("CONNECT 0")).value shouldBe ascii("CONNECT 0\r\n")
    }
    "refuse what could not be read back as the same item" in {
      Gs1500mSerial.encode(StatusLine("")).isLeft shouldBe true
      Gs1500mSerial.encode(StatusLine("two\r\nlines")).isLeft shouldBe true
      Gs1500mSerial.encode(StatusLine("x" * 257)).isLeft shouldBe true
      Gs1500mSerial.encode(OtherReply('Z')).left.value shouldBe SerialError.BadReplyLetter('Z')
      Gs1500mSerial.encode(OtherReply('O')).left.value shouldBe SerialError.BadReplyLetter('O')
      Gs1500mSerial.encode(OtherReply('1')).left.value shouldBe SerialError.BadReplyLetter('1')
    }
  }

  "The decoder" should {
    "read a UDP server header's sender, also with a colon, and still deliver data with an unreadable sender" in {
      SerialDecoder.decodeAll(ascii(s"${Esc}y010.0.0.7 11011\t0002hi").toArray) shouldBe
        Vector(Data(0, Some(Remote("10.0.0.7", 11011)), ascii("hi")))
      SerialDecoder.decodeAll(ascii(s"${Esc}yb10.0.0.7:3838\t0001!").toArray) shouldBe
        Vector(Data(11, Some(Remote("10.0.0.7", 3838)), ascii("!")))
      SerialDecoder.decodeAll(ascii(s"${Esc}y2somewhere\t0001!").toArray) shouldBe Vector(Data(2, None, ascii("!")))
    }
    "treat data bytes as data, ESC and line ends included" in {
      val data = ascii(s"a${Esc}Z00005\r\nb")
      SerialDecoder.decodeAll((Gs1500mSerial.encodeBulk(1, data).value).toArray) shouldBe Vector(Data(1, None, data))
    }
    "deliver empty datagrams" in {
      SerialDecoder.decodeAll(ascii(s"${Esc}Z30000${Esc}O").toArray) shouldBe Vector(Data(3, None, ArraySeq.empty), Ack)
    }
    "read two-byte replies between datagrams, as the thesis's parser drops them" in {
      val stream = ascii(s"${Esc}O") ++ Gs1500mSerial.encodeBulk(0, ascii("x")).value ++ ascii(s"${Esc}F${Esc}k")
      SerialDecoder.decodeAll(stream.toArray) shouldBe Vector(Ack, Data(0, None, ascii("x")), Fail, OtherReply('k'))
    }
    "read status lines split anywhere, dropping CRs and empty lines" in {
      val stream = ascii("\r\nCONNECT 0\r\n\r\n\nDISCONNECT 0\r\n")
      forAll(Gen.listOf(Gen.choose(1, 6))) { sizes =>
        decodeChunked(stream, sizes)._2 shouldBe Vector(StatusLine("CONNECT 0"), StatusLine("DISCONNECT 0"))
      }
    }
    "resynchronise on the next ESC after garbage" in {
      val frame = Gs1500mSerial.encodeBulk(0, ascii("payload")).value
      SerialDecoder.decodeAll((hex("01 02 FF 80") ++ frame).toArray) shouldBe
        Vector(Garbage(4), Data(0, None, ascii("payload")))
      // A bad cid, a non-digit length and an oversize length are garbage up to the next ESC.
      for (bad <- Seq(s"${Esc}Zg0001x", s"${Esc}Z00x01x", s"${Esc}Z09999abc"))
        SerialDecoder.decodeAll((ascii(bad) ++ frame).toArray) shouldBe
          Vector(Garbage(bad.length), Data(0, None, ascii("payload")))
      // A UDP server header without a TAB within 31 characters is garbage too.
      val noTab = s"${Esc}y0" + "1" * 40
      SerialDecoder.decodeAll((ascii(noTab) ++ frame).toArray) shouldBe
        Vector(Garbage(noTab.length), Data(0, None, ascii("payload")))
    }
    "read the next line again after a broken one" in {
      SerialDecoder.decodeAll(ascii("CONN\u0001ECT 0\r\nDISCONNECT 1\r\n").toArray) shouldBe
        Vector(Garbage(12), StatusLine("DISCONNECT 1"))
    }
    "count a datagram whose header was overwritten as garbage and read the next one intact" in {
      val older = Gs1500mSerial.encode(Data(0, Some(Remote("10.0.0.1", 5000)), ascii("A" * 100))).value
      val newer = Gs1500mSerial.encode(Data(0, Some(Remote("10.0.0.1", 5000)), ascii("B" * 100))).value
      val tail = older.drop(30)
      SerialDecoder.decodeAll((tail ++ newer).toArray) shouldBe
        Vector(Garbage(tail.length), Data(0, Some(Remote("10.0.0.1", 5000)), ascii("B" * 100)))
    }
    "take an ESC before a non-letter for one garbage byte and read the byte afresh" in {
      SerialDecoder.decodeAll(ascii(s"${Esc}1 ok\r\n${Esc}${Esc}O").toArray) shouldBe
        Vector(Garbage(1), StatusLine("1 ok"), Garbage(1), Ack)
    }
    "keep garbage pending until the next item" in {
      val (decoder, events) = SerialDecoder.empty.feed(hex("00 01 02"))
      events shouldBe empty
      decoder.pendingGarbage shouldBe 3
      decoder.isIdle shouldBe false
    }
  }

  private val genRemote: Gen[Remote] = for {
    octets <- Gen.listOfN(4, Gen.choose(0, 255))
    port <- Gen.choose(0, 65535)
  } yield Remote(octets.mkString("."), port)

  private val genBytes: Gen[ArraySeq[Byte]] =
    Gen.frequency(4 -> Gen.choose(0, 40), 1 -> Gen.choose(0, 1400)).flatMap { n =>
      Gen.listOfN(n, Arbitrary.arbitrary[Byte]).map(bs => ArraySeq.unsafeWrapArray(bs.toArray))
    }

  private val genItem: Gen[SerialItem] = Gen.frequency(
    5 -> (for {
      cid <- Gen.choose(0, 15)
      remote <- Gen.option(genRemote)
      bytes <- genBytes
    } yield Data(cid, remote, bytes)),
    1 -> Gen.const(Ack),
    1 -> Gen.const(Fail),
    1 -> Gen.oneOf(('A' to 'Z') ++ ('a' to 'z')).suchThat(c => !"ZyOF".contains(c)).map(OtherReply(_)),
    2 -> Gen
      .nonEmptyListOf(Gen.frequency(9 -> Gen.choose(0x20, 0x7e), 1 -> Gen.const('\t'.toInt)))
      .map(cs => StatusLine(cs.take(120).map(_.toChar).mkString))
  )

  private val genChunks: Gen[List[Int]] = Gen.listOf(Gen.frequency(3 -> Gen.choose(1, 8), 1 -> Gen.choose(1, 2000)))

  // Bytes that exercise every branch: ESC, header letters, digits, TAB, line ends, plus anything at all.
  private val genNoise: Gen[ArraySeq[Byte]] = Gen
    .listOf(Gen.frequency(
        5 -> Arbitrary.arbitrary[Byte],
        3 -> Gen.oneOf("\u001bZyOF0123456789af. \t\r\nCONNECT".toSeq).map(_.toByte)
      ))
    .map(bs => ArraySeq.unsafeWrapArray(bs.toArray))

  "Encoding then decoding" should {
    "give back every item, however the serial bytes are chunked" in {
      forAll(Gen.listOf(genItem), genChunks) { (items, chunks) =>
        val stream = items.map(Gs1500mSerial.encode(_).value).foldLeft(ArraySeq.empty[Byte])(_ ++ _)
        val (decoder, events) = decodeChunked(stream, chunks)
        events shouldBe items.toVector
        decoder.isIdle shouldBe true
      }
    }
  }

  "Arbitrary serial bytes" should {
    "never make the decoder throw, and give the same events however they are chunked" in {
      forAll(genNoise, genChunks) { (bytes, chunks) =>
        val (whole, wholeEvents) = SerialDecoder.empty.feed(bytes)
        val (split, splitEvents) = decodeChunked(bytes, chunks)
        splitEvents shouldBe wholeEvents
        split.pendingGarbage shouldBe whole.pendingGarbage
        split.toString shouldBe whole.toString
        wholeEvents.foreach {
          case Garbage(n) => n should be > 0
          case Data(cid, _, data) =>
            cid should (be >= 0 and be <= 15)
            data.length should be <= 1400
          case _ =>
        }
      }
    }
    "be followed by a frame that is still read intact once an ESC comes" in {
      forAll(genNoise.map(_.filter(_ != 27)), genItem.suchThat(_.isInstanceOf[Data]), genChunks) {
        (noise, item, chunks) =>
          val events = decodeChunked(noise ++ Gs1500mSerial.encode(item).value, chunks)._2
          events.last shouldBe item
          all(events.init.map(_.getClass.getSimpleName)) should (be("Garbage") or be("StatusLine"))
      }
    }
  }
}
