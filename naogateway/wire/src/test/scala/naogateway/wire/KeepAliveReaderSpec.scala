package naogateway.wire

import com.google.protobuf.{ByteString, CodedOutputStream}
import org.scalacheck.{Arbitrary, Gen}
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.proto.{Position, Status}

/** The one-pass keep-alive reader gives exactly what the general path (normalize, then decode) gives, or leaves it. */
class KeepAliveReaderSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {
  import MessageGenerators._

  implicit override val generatorDrivenConfig: PropertyCheckConfiguration =
    PropertyCheckConfiguration(minSuccessful = 500)

  private def general(b: Array[Byte]) = MessageContents.general(b, 0, b.length)

  private val keepAlive: Gen[MessageContents] = for {
    robotId <- Arbitrary.arbitrary[Int]
    s <- Gen.option(status)
    h <- Gen.option(robotHealth)
    t <- Gen.option(servoTelemetry)
  } yield MessageContents(robotId, status = s, robotHealth = h, servoTelemetry = t)

  /** Bytes a hostile or broken sender might make of a keep-alive: flipped, cut, grown, spliced. */
  private def mutated(bytes: Array[Byte]): Gen[Array[Byte]] = {
    val at = Gen.choose(0, math.max(0, bytes.length - 1))
    Gen.oneOf(
      for { i <- at; b <- Arbitrary.arbitrary[Byte] } yield { val c = bytes.clone(); if (c.nonEmpty) c(i) = b; c },
      at.map(i => bytes.take(i)),
      for { i <- at; b <- Gen.listOfN(3, Arbitrary.arbitrary[Byte]) } yield bytes.take(i) ++ b ++ bytes.drop(i),
      Gen.listOfN(6, Arbitrary.arbitrary[Byte]).map(bytes ++ _),
      for { i <- at; b <- Gen.oneOf(0x80, 0xc0, 0xed, 0xff, 0xf8) } yield {
        val c = bytes.clone(); if (c.nonEmpty) c(i) = b.toByte; c
      }
    )
  }

  private def field(number: Int, wireType: Int)(write: CodedOutputStream => Unit): Array[Byte] = {
    val out = new java.io.ByteArrayOutputStream()
    val cos = CodedOutputStream.newInstance(out)
    cos.writeTag(number, wireType)
    write(cos)
    cos.flush()
    out.toByteArray
  }
  private def delimited(number: Int, body: Array[Byte]) = field(number, 2)(_.writeByteArrayNoTag(body))
  private def varint(number: Int, v: Long) = field(number, 0)(_.writeUInt64NoTag(v))
  private val robot1 = varint(1, 1)

  "The keep-alive reader" should {
    "read every keep-alive itself, as the general path reads it" in {
      forAll(keepAlive) { c =>
        val bytes = c.toProtobuf
        KeepAliveReader.read(bytes, 0, bytes.length) shouldBe c
        general(bytes) shouldBe Right(c)
      }
    }

    "agree with the general path on any message and on broken keep-alives" in {
      // A NaN (a mutated float) is not equal to itself: each reading is compared by what it encodes to.
      def encoded(r: Either[Any, MessageContents]): Either[Any, Vector[Byte]] = r.map(_.toProtobuf.toVector)
      forAll(contents) { c =>
        val bytes = c.toProtobuf
        encoded(MessageContents.parse(bytes)) shouldBe encoded(general(bytes))
      }
      forAll(keepAlive.map(_.toProtobuf).flatMap(mutated)) { bytes =>
        encoded(MessageContents.parse(bytes)) shouldBe encoded(general(bytes))
      }
    }

    "read a keep-alive whose rotation is NaN as the general path does" in {
      // Found by the property above (shrunk): a Position whose rotation is NaN, and an unknown field in Status.
      val bytes =
        Array(8, 0, -70, 1, 52, 24, -1, -1, 0, 58, 18, 8, 0, 8, -1, -1, -1, -1, -1, -1, -1, -1, -1, 0, 29, 0, 0,
          -1, -1, 65, 0, 0, 0, 0, 0, 0, 0, 0, 122, 6, 0, 0, 0, 0, 0, 0, -3, 0, 0, 0, 0, 0, -8, 0, 0, 24, 0).map(
          _.toByte)
      val fast = MessageContents.parse(bytes)
      val slow = general(bytes)
      fast.isRight shouldBe true
      fast.map(_.status.flatMap(_.robotPosition).flatMap(_.rotation).exists(_.isNaN)) shouldBe Right(true)
      fast.map(_.toProtobuf.toVector) shouldBe slow.map(_.toProtobuf.toVector)
    }

    "leave an overlong ten-byte varint to the general path and agree with it" in {
      // Found by the property above (shrunk): Status.timestamp as nine FF bytes and a tenth 00. protobuf-java reads
      // the top bit of such a varint one way or the other depending on where it lies; the reader must not guess.
      val bytes =
        Array(8, 0, -70, 1, 125, 8, -1, -1, -1, -1, -1, -1, -1, -1, -1, 0, 16, -1, -1, -1, -1, 0, 24, 0, 58, 16,
          8, -1, -1, -1, -1, 0, 8, -1, -1, -1, 0, 29, 0, 0, 0, 0, 65, 0, 0, 0, 0, 0, 0, 0, 0, 98, 55) ++ Array.fill(55)(
          0) ++
          Array(122, 13) ++ Array.fill(13)(0) ++ Array(-126, 1, 4, 0, 0, 0, 0)
      val frame = bytes.map(_.toByte)
      KeepAliveReader.read(frame, 0, frame.length) shouldBe null
      MessageContents.parse(frame).map(_.toProtobuf.toVector) shouldBe general(frame).map(_.toProtobuf.toVector)
      // The canonical form of a number with the top bit set (tenth byte 01) is still read here.
      val negative = robot1 ++ delimited(23, varint(1, -1L))
      KeepAliveReader.read(negative, 0, negative.length) shouldBe MessageContents(1,
        status = Some(Status(timestamp = Some(-1L))))
    }

    "read a malformed string as U+FFFD itself (protocol.md 5)" in {
      val bad = robot1 ++ delimited(23, field(12, 2)(_.writeByteArrayNoTag(Array(0x41, 0xff, 0x42).map(_.toByte))))
      val expected = MessageContents(1, status = Some(Status(activeAgent = Some("A\uFFFDB"))))
      KeepAliveReader.read(bad, 0, bad.length) shouldBe expected
      general(bad) shouldBe Right(expected)
    }

    "leave to the general path what it does not read plainly, with the same outcome" in {
      val position = Position(x = Some(3)).toByteArray
      val cases = Seq(
        "a uint32 beyond 32 bits" -> (robot1 ++ delimited(23, varint(2, 1L << 32))),
        "a robotID beyond int32" -> varint(1, 1L << 40),
        "no robotID" -> delimited(23, varint(2, 1)),
        "a group inside Status" -> (robot1 ++ delimited(23,
          field(5, 3)(_ => ()) ++ field(5, 4)(_ => ()) ++ varint(2, 7))),
        "an unknown field in Status" -> (robot1 ++ delimited(23, varint(40, 9))),
        "Status twice (merged)" -> (robot1 ++ delimited(23, varint(2, 1)) ++ delimited(23, varint(3, 2))),
        "Position twice (merged)" -> (robot1 ++ delimited(23, delimited(7, position) ++ delimited(7, varint(2, 5)))),
        "an unknown extension" -> (robot1 ++ varint(7150, 1)),
        "a truncated Status" -> (robot1 ++ delimited(23, varint(2, 1))).dropRight(1),
        "a field of the wrong wire type" -> (robot1 ++ delimited(23,
          field(2, 2)(_.writeBytesNoTag(ByteString.copyFromUtf8("x"))))),
        "a servo without its required id" -> (robot1 ++ delimited(7106, delimited(1, varint(2, 512)))),
        "a servo load beyond sint32" -> (robot1 ++ delimited(7106, delimited(1, varint(1, 3) ++ varint(3, 1L << 33)))),
        "an unknown field in a servo" -> (robot1 ++ delimited(7106, delimited(1, varint(1, 3) ++ varint(9, 1))))
      )
      cases.foreach { case (what, bytes) =>
        withClue(what) {
          KeepAliveReader.read(bytes, 0, bytes.length) shouldBe null
          MessageContents.parse(bytes) shouldBe general(bytes)
        }
      }
      MessageContents.parse(cases(5)._2).map(_.status) shouldBe Right(Some(Status(teamID = Some(1),
            timeOnline = Some(2))))
      MessageContents.parse(cases(0)._2).isLeft shouldBe true
    }
  }
}
