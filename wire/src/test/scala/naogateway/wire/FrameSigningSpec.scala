package naogateway.wire

import org.scalacheck.{Arbitrary, Gen}
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.proto.{Message, MessageProto}

class FrameSigningSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {

  private val teamKey =
    SigningKey.fromHex("000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f").toOption.get
  private val otherTeamKey =
    SigningKey.fromHex("ff0102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f").toOption.get
  private val R = SignDirection.RobotToGateway

  private val contents: Gen[MessageContents] = for {
    id <- Gen.choose(0, 40)
    status <- Gen.option(MessageGenerators.status)
    health <- Gen.option(MessageGenerators.robotHealth)
  } yield MessageContents(id, status = status, robotHealth = health)

  private def verify(body: Array[Byte], k: SigningKey = teamKey, d: SignDirection = R) =
    FrameSigning.verify(body, 0, body.length, k, d)

  "A signed body" should {
    "verify with the same teamKey and direction, covering exactly the unsigned bytes" in {
      forAll(contents, Arbitrary.arbitrary[Long]) { (c, ts) =>
        val body = c.toProtobuf
        verify(FrameSigning.sign(body, teamKey, R, ts)) shouldBe Right(SignedBody(ts, body.length))
      }
    }

    "be refused when any covered byte changes, with another teamKey, or in the other direction" in {
      forAll(contents, Arbitrary.arbitrary[Long], Gen.choose(0, 10000), Gen.choose(1, 255)) { (c, ts, at, flip) =>
        val signed = FrameSigning.sign(c.toProtobuf, teamKey, R, ts)
        val i = at % signed.length
        val altered = signed.clone()
        altered(i) = (altered(i) ^ flip).toByte
        verify(altered).isRight shouldBe false
        verify(signed, otherTeamKey) shouldBe Left(SignatureError.BadMac)
        verify(signed, teamKey, SignDirection.GatewayToRobot) shouldBe Left(SignatureError.BadMac)
      }
    }

    "still decode for a peer that does not sign: the signature is an unknown extension it skips" in {
      forAll(contents, Arbitrary.arbitrary[Long]) { (c, ts) =>
        val signed = FrameSigning.sign(c.toProtobuf, teamKey, R, ts)
        val decoded = MessageContents.parse(signed).toOption.get
        decoded.copy(unknownExtensions = Vector.empty) shouldBe c
        decoded.unknownExtensions shouldBe Vector(FrameSigning.Field)
        // The generated protobuf classes read it as the FrameSignature extension.
        Message.parseFrom(signed).extension(MessageProto.signature).map(_.timestamp) shouldBe Some(ts)
      }
    }

    "be refused when unsigned, when a field follows the signature, or when the signature is malformed" in {
      val body = MessageContents(3).toProtobuf
      verify(body) shouldBe Left(SignatureError.Missing)
      val signed = FrameSigning.sign(body, teamKey, R, 1L)
      verify(signed ++ Array[Byte](0x08, 0x05)) shouldBe Left(SignatureError.NotLast)
      // A 7-byte mac: the same field with one byte short.
      val short = signed.clone()
      short(signed.length - 20) = 18
      short(signed.length - 9) = 7
      verify(short.dropRight(1)) shouldBe Left(SignatureError.Malformed)
    }
  }

  "A signed frame" should {
    "be the same whether signed from its contents or from its encoded unsigned frame, in both header forms" in {
      forAll(contents, Arbitrary.arbitrary[Long], Gen.oneOf(HeaderForm.Legacy, HeaderForm.Compact)) { (c, ts, form) =>
        val encoded = MessageContents.encodeFrame(c, form).toOption.get
        val signed = FrameSigning.signEncoded(encoded, teamKey, R, ts)
        signed.map(_.toVector) shouldBe FrameSigning.signFrame(c, form, teamKey, R, ts).map(_.toVector)
        val header = FumanoidsFrame.decodeHeader(signed.toOption.get).toOption.get
        header.form shouldBe form
        header.gzip shouldBe false
        FrameSigning.verifyFrame(signed.toOption.get, header, teamKey, R) shouldBe Right(SignedBody(ts,
            c.toProtobuf.length))
        MessageContents.decodeFrame(signed.toOption.get).map(
          _._2.copy(unknownExtensions = Vector.empty)) shouldBe Right(c)
      }
    }

    "not be made from a gzip-flagged frame, and be checked after inflating one that arrives" in {
      val c = MessageContents(2, status = Some(naogateway.proto.Status(teamID = Some(1))))
      FrameSigning.signEncoded(MessageContents.encodeFrame(c, gzip = true).toOption.get, teamKey, R, 1L).isLeft shouldBe true
      val zipped =
        FumanoidsFrame.encodeProtobuf(FrameSigning.sign(c.toProtobuf, teamKey, R, 3L), gzip = true).toOption.get
      val header = FumanoidsFrame.decodeHeader(zipped).toOption.get
      FrameSigning.verifyFrame(zipped, header, teamKey, R).map(_.timestamp) shouldBe Right(3L)
    }
  }

  "The replay window" should {
    "accept only timestamps above the last accepted one, as unsigned numbers" in {
      forAll(Gen.listOf(Arbitrary.arbitrary[Long])) { stamps =>
        var window = ReplayWindow.empty
        var accepted = Vector.empty[Long]
        stamps.foreach(ts => window.accept(ts).foreach { w => window = w; accepted :+= ts })
        accepted.sliding(2).foreach {
          case Vector(a, b) => java.lang.Long.compareUnsigned(a, b) should be < 0
          case _            => ()
        }
        stamps.headOption.foreach(first => accepted.headOption shouldBe Some(first))
      }
    }

    "order a robot's reboots above its earlier frames" in {
      val beforeReboot = FrameSigning.robotTimestamp(bootCounter = 7, frameCounter = 0xfffffff0L)
      val afterReboot = FrameSigning.robotTimestamp(bootCounter = 8, frameCounter = 0)
      ReplayWindow(Some(beforeReboot)).accept(afterReboot).isRight shouldBe true
      ReplayWindow(Some(afterReboot)).accept(beforeReboot) shouldBe Left(SignatureError.Replayed)
    }
  }

  "A signing teamKey" should {
    "refuse short or non-hex keys without echoing the digits, and never print itself" in {
      SigningKey.fromHex("00112233").left.toOption.get should include("at least 16 bytes")
      SigningKey.fromHex("zz" * 16).left.toOption.get should not include "zz"
      teamKey.toString should not include "0001"
    }
  }
}
