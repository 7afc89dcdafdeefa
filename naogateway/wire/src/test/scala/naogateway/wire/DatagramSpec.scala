package naogateway.wire

import java.nio.charset.StandardCharsets

import org.scalacheck.{Arbitrary, Gen}
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.wire.Datagram.Rejection
import naogateway.wire.gamecontroller.{GameControllerCodec, GameControllerGenerators, ReturnData, ReturnMessage}

/** Each kind and each rejection of the datagram classifier, and that the kinds never overlap. */
class DatagramSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {

  implicit override val generatorDrivenConfig: PropertyCheckConfiguration =
    PropertyCheckConfiguration(minSuccessful = 2000)

  private def ascii(s: String): Array[Byte] = s.getBytes(StandardCharsets.US_ASCII)
  private def bytesOf(values: Int*): Array[Byte] = values.map(_.toByte).toArray
  private def sized(prefix: Array[Byte], size: Int): Array[Byte] = java.util.Arrays.copyOf(prefix, size)

  // docs/protocol.md 9.1: the worked FU-Remote frame of the thesis (legacy header).
  private val workedFrame =
    bytesOf(0x00, 0x2a, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x12, 0x08, 0x01, 0xba, 0x01, 0x0d, 0x10, 0x01, 0x62, 0x09) ++
      ascii("AgentTest")

  private val predicates: List[(String, Array[Byte] => Boolean)] = List(
    "FU-Remote frame" -> Datagram.isFuRemoteFrame,
    "GameController control" -> Datagram.isGameControllerControl,
    "GameController return" -> Datagram.isGameControllerReturn,
    "stream segment" -> Datagram.isStreamSegment
  )

  private def kindOf(datagram: Datagram): Option[String] = datagram match {
    case Datagram.FuRemoteFrame(_)         => Some("FU-Remote frame")
    case Datagram.GameControllerControl(_) => Some("GameController control")
    case Datagram.GameControllerReturn(_)  => Some("GameController return")
    case Datagram.StreamSegment(_)         => Some("stream segment")
    case Datagram.Rejected(_, _)           => None
  }

  private def rejection(bytes: Array[Byte]): Rejection = Datagram.classify(bytes) match {
    case Datagram.Rejected(reason, same) =>
      same should be theSameInstanceAs bytes
      reason
    case other => fail(s"expected a rejection, got $other")
  }

  // Arbitrary bytes rarely hit a prefix, so most cases start with one (or with a near miss) and have
  // lengths around every boundary: 0..8 bytes, up to a GameController packet, and around 1400.
  private val prefixes: Gen[Array[Byte]] = Gen.oneOf(
    Gen.const(Array.emptyByteArray),
    Gen.const(bytesOf(0x00, 0x2a)),
    Gen.const(ascii("RGme")),
    Gen.const(ascii("RGrt")),
    Gen.const(ascii("RG")),
    Gen.const(ascii("R")),
    Gen.const(bytesOf(0x00)),
    Gen.const(bytesOf(0x2a, 0x00)),
    Gen.const(bytesOf(0x29, 0x2a)),
    for { a <- Gen.choose(0, 41); b <- Gen.choose(0, 41) } yield bytesOf(a, b),
    for { a <- Gen.choose(0, 255); b <- Gen.choose(0, 255) } yield bytesOf(a, b),
    for { c <- Gen.alphaChar; d <- Gen.alphaChar } yield ascii(s"RG$c$d")
  )
  private val lengths: Gen[Int] = Gen.frequency(
    4 -> Gen.choose(0, 10),
    3 -> Gen.choose(0, 200),
    2 -> Gen.choose(1390, 1410),
    1 -> Gen.choose(0, 2000)
  )
  private val datagrams: Gen[Array[Byte]] = for {
    prefix <- prefixes
    length <- lengths
    tail <- Gen.containerOfN[Array, Byte](length, Arbitrary.arbitrary[Byte])
  } yield (prefix ++ tail).take(math.max(length, 0))

  "Datagram.classify" should {
    "recognise FU-Remote frames from 8 to 1400 bytes" in {
      Datagram.classify(workedFrame) shouldBe Datagram.FuRemoteFrame(workedFrame)
      val smallest = bytesOf(0x00, 0x2a, 0, 0, 0, 0, 0, 0x12)
      Datagram.classify(smallest) should matchPattern { case Datagram.FuRemoteFrame(b) if b eq smallest => }
      val largest = sized(bytesOf(0x00, 0x2a), 1400)
      Datagram.classify(largest) should matchPattern { case Datagram.FuRemoteFrame(b) if b eq largest => }
    }
    "recognise GameController control packets of both versions" in {
      forAll(GameControllerGenerators.control) { data =>
        val bytes = GameControllerCodec.encodeControl(data).fold(err => fail(err.describe), identity)
        Datagram.classify(bytes) should matchPattern { case Datagram.GameControllerControl(b) if b eq bytes => }
      }
    }
    "classify by prefix only, leaving sizes and versions to the codec" in {
      val bare = ascii("RGme")
      Datagram.classify(bare) should matchPattern { case Datagram.GameControllerControl(b) if b eq bare => }
      val bareReturn = ascii("RGrt")
      Datagram.classify(bareReturn) should matchPattern { case Datagram.GameControllerReturn(b) if b eq bareReturn => }
    }
    "recognise GameController return packets" in {
      val bytes = GameControllerCodec.encodeReturn(ReturnData(12, 2, ReturnMessage.Alive)).toOption.get
      Datagram.classify(bytes) should matchPattern { case Datagram.GameControllerReturn(b) if b eq bytes => }
    }
    "recognise secure-stream segments: pure ACKs and data, sequence and ACK 0..41" in {
      for { seq <- 0 to 41; ack <- 0 to 41 } {
        val pureAck = bytesOf(seq, ack)
        Datagram.classify(pureAck) should matchPattern { case Datagram.StreamSegment(b) if b eq pureAck => }
      }
      val data = sized(bytesOf(41, 41), 1400)
      Datagram.classify(data) should matchPattern { case Datagram.StreamSegment(b) if b eq data => }
    }
    "reject an empty datagram" in {
      rejection(Array.emptyByteArray) shouldBe Rejection.Empty
    }
    "reject a single byte as too short for any kind" in {
      (0 to 255).foreach(b => rejection(bytesOf(b)) shouldBe Rejection.TooShort(1, 2))
    }
    "reject an FU-Remote prefix shorter than its 8-byte header" in {
      (2 to 7).foreach(n => rejection(sized(bytesOf(0x00, 0x2a), n)) shouldBe Rejection.TooShort(n, 8))
    }
    "reject an RG prefix too short to name its type" in {
      rejection(ascii("RG")) shouldBe Rejection.TooShort(2, 4)
      rejection(ascii("RGm")) shouldBe Rejection.TooShort(3, 4)
    }
    "reject every datagram over 1400 bytes, whatever its prefix" in {
      List(bytesOf(0x00, 0x2a), ascii("RGme"), ascii("RGrt"), bytesOf(0, 0), bytesOf(0xff, 0xff)).foreach { prefix =>
        rejection(sized(prefix, 1401)) shouldBe Rejection.Oversize(1401, 1400)
        rejection(sized(prefix, 65507)) shouldBe Rejection.Oversize(65507, 1400)
      }
    }
    "reject RG followed by an unknown type" in {
      rejection(ascii("RGxx")) shouldBe Rejection.UnknownGameControllerType('x'.toInt, 'x'.toInt)
      rejection(ascii("RGmE")) shouldBe Rejection.UnknownGameControllerType('m'.toInt, 'E'.toInt)
      rejection(ascii("RGrt").updated(2, 0x80.toByte)) shouldBe Rejection.UnknownGameControllerType(0x80, 't'.toInt)
    }
    "reject unknown prefixes, with the bytes read unsigned" in {
      rejection(bytesOf(0xff, 0xff, 1, 2)) shouldBe Rejection.UnknownPrefix(255, 255)
      rejection(bytesOf(42, 0)) shouldBe Rejection.UnknownPrefix(42, 0)
      rejection(bytesOf(0, 42 + 1)) shouldBe Rejection.UnknownPrefix(0, 43)
      rejection(bytesOf(41, 42)) shouldBe Rejection.UnknownPrefix(41, 42)
      rejection(ascii("RH")) shouldBe Rejection.UnknownPrefix('R'.toInt, 'H'.toInt)
      rejection(ascii("rGme")) shouldBe Rejection.UnknownPrefix('r'.toInt, 'G'.toInt)
    }
    "give every rejection a description" in {
      List(
        Rejection.Empty,
        Rejection.TooShort(1, 2),
        Rejection.Oversize(1401, 1400),
        Rejection.UnknownGameControllerType(1, 2),
        Rejection.UnknownPrefix(3, 4)
      ).foreach(_.describe should not be empty)
    }
  }

  "The classification predicates" should {
    "be mutually exclusive for arbitrary bytes, and classify agrees with the one that holds" in {
      forAll(datagrams) { bytes =>
        val holding = predicates.collect { case (name, p) if p(bytes) => name }
        holding.size should be <= 1
        val result = Datagram.classify(bytes)
        kindOf(result) shouldBe holding.headOption
        result.bytes should be theSameInstanceAs bytes
      }
    }
    "be mutually exclusive for every two-byte prefix" in {
      for { a <- 0 to 255; b <- 0 to 255; size <- List(2, 4, 8) } {
        val bytes = sized(bytesOf(a, b), size)
        predicates.count { case (_, p) => p(bytes) } should be <= 1
      }
    }
    "never throw, for arbitrary bytes" in {
      forAll(GameControllerGenerators.bytes(2000)) { bytes =>
        noException should be thrownBy {
          Datagram.classify(bytes)
          predicates.foreach { case (_, p) => p(bytes) }
        }
      }
    }
  }
}
