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
  private val robot7 = teamKey.robotKey(7)
  private val R: SignedLink = SignedLink.FromRobot(7)

  private val contents: Gen[MessageContents] = for {
    id <- Gen.choose(0, 40)
    status <- Gen.option(MessageGenerators.status)
    health <- Gen.option(MessageGenerators.robotHealth)
  } yield MessageContents(id, status = status, robotHealth = health)

  private def verify(body: Array[Byte], k: RobotKey = robot7, l: SignedLink = R) =
    FrameSigning.verify(body, 0, body.length, k, l)

  private def hex(s: String): Array[Byte] = s.grouped(2).map(Integer.parseInt(_, 16).toByte).toArray

  "A signed body" should {
    "verify with the same robot key and link, covering exactly the unsigned bytes" in {
      forAll(contents, Arbitrary.arbitrary[Long]) { (c, ts) =>
        val body = c.toProtobuf
        verify(FrameSigning.sign(body, robot7, R, ts)) shouldBe Right(SignedBody(ts, body.length))
      }
    }

    "be refused when any covered byte changes, with another key, for another robot or epoch, or the other way" in {
      forAll(contents, Arbitrary.arbitrary[Long], Gen.choose(0, 10000), Gen.choose(1, 255)) { (c, ts, at, flip) =>
        val signed = FrameSigning.sign(c.toProtobuf, robot7, R, ts)
        val i = at % signed.length
        val altered = signed.clone()
        altered(i) = (altered(i) ^ flip).toByte
        verify(altered).isRight shouldBe false
        verify(signed, otherTeamKey.robotKey(7)) shouldBe Left(SignatureError.BadMac)
        verify(signed, robot7, SignedLink.ToRobot(7, FrameSigning.epochOf(ts))) shouldBe Left(SignatureError.BadMac)
        // Robot 8's key, or robot 7's key with robot 8 in the MAC input: neither opens robot 7's frame.
        verify(signed, teamKey.robotKey(8), SignedLink.FromRobot(8)) shouldBe Left(SignatureError.BadMac)
        verify(signed, robot7, SignedLink.FromRobot(8)) shouldBe Left(SignatureError.BadMac)
      }
    }

    "bind the gateway's frames to the robot's boot epoch" in {
      forAll(contents, Arbitrary.arbitrary[Long], Arbitrary.arbitrary[Int]) { (c, ts, epoch) =>
        val link = SignedLink.ToRobot(7, epoch)
        val signed = FrameSigning.sign(c.toProtobuf, robot7, link, ts)
        verify(signed, robot7, link) shouldBe Right(SignedBody(ts, c.toProtobuf.length))
        verify(signed, robot7, SignedLink.ToRobot(7, epoch + 1)) shouldBe Left(SignatureError.BadMac)
      }
    }

    "still decode for a peer that does not sign: the signature is an unknown extension it skips" in {
      forAll(contents, Arbitrary.arbitrary[Long]) { (c, ts) =>
        val signed = FrameSigning.sign(c.toProtobuf, robot7, R, ts)
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
      val signed = FrameSigning.sign(body, robot7, R, 1L)
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
        val signed = FrameSigning.signEncoded(encoded, robot7, R, ts)
        signed.map(_.toVector) shouldBe FrameSigning.signFrame(c, form, robot7, R, ts).map(_.toVector)
        val header = FumanoidsFrame.decodeHeader(signed.toOption.get).toOption.get
        header.form shouldBe form
        header.gzip shouldBe false
        FrameSigning.verifyFrame(signed.toOption.get, header, robot7, R) shouldBe Right(SignedBody(ts,
            c.toProtobuf.length))
        MessageContents.decodeFrame(signed.toOption.get).map(
          _._2.copy(unknownExtensions = Vector.empty)) shouldBe Right(c)
      }
    }

    "not be made from a gzip-flagged frame, and be checked after inflating one that arrives" in {
      val c = MessageContents(2, status = Some(naogateway.proto.Status(teamID = Some(1))))
      FrameSigning.signEncoded(MessageContents.encodeFrame(c, gzip = true).toOption.get, robot7, R, 1L).isLeft shouldBe true
      val zipped =
        FumanoidsFrame.encodeProtobuf(FrameSigning.sign(c.toProtobuf, robot7, R, 3L), gzip = true).toOption.get
      val header = FumanoidsFrame.decodeHeader(zipped).toOption.get
      FrameSigning.verifyFrame(zipped, header, robot7, R).map(_.timestamp) shouldBe Right(3L)
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
      val beforeReboot = FrameSigning.robotTimestamp(bootEpoch = 7, frameCounter = 0xfffffff0L)
      val afterReboot = FrameSigning.robotTimestamp(bootEpoch = 8, frameCounter = 0)
      ReplayWindow(Some(beforeReboot)).accept(afterReboot).isRight shouldBe true
      ReplayWindow(Some(afterReboot)).accept(beforeReboot) shouldBe Left(SignatureError.Replayed)
    }
  }

  "A team key" should {
    "refuse short, long, odd or non-hex keys without echoing the digits, and never print itself" in {
      SigningKey.fromHex("00112233").left.toOption.get should include("at least 16 bytes")
      SigningKey.fromHex("ab" * 65).left.toOption.get should include("at most 64 bytes")
      SigningKey.fromHex("abc" * 11).left.toOption.get should include("even number")
      SigningKey.fromHex("zz" * 16).left.toOption.get should not include "zz"
      SigningKey.fromHex("ab" * 16).isRight shouldBe true
      SigningKey.fromHex("ab" * 64).isRight shouldBe true
      teamKey.toString should not include "0001"
      teamKey.robotKey(1).toString should not include teamKey.robotKey(1).toHex.take(4)
    }

    "derive a robot key per robot id, each one its own" in {
      val keys = (0 to 20).map(teamKey.robotKey) :+ teamKey.robotKey(-1)
      keys.map(_.toHex).distinct.size shouldBe keys.size
      keys.foreach(_.toHex.length shouldBe 64)
      teamKey.robotKey(3) shouldBe teamKey.robotKey(3)
      otherTeamKey.robotKey(3) should not be teamKey.robotKey(3)
      RobotKey.fromHex(3, teamKey.robotKey(3).toHex) shouldBe Right(teamKey.robotKey(3))
    }
  }

  "HKDF-SHA256" should {
    "give RFC 5869's test case 1 (Appendix A.1)" in {
      val ikm = hex("0b" * 22)
      val salt = hex("000102030405060708090a0b0c")
      val info = hex("f0f1f2f3f4f5f6f7f8f9")
      val prk = Hkdf.extract(salt, ikm)
      prk.toVector shouldBe hex("077709362c2e32df0ddc3f0dc47bba6390b6c73bb50f9c3122ec844ad7c2b3e5").toVector
      Hkdf.expand(prk, info, 42).toVector shouldBe
        hex("3cb25f25faacd57a90434f64d0362f2a2d2d0a90cf1a5a4c5db02d56ecc4c5bf34007208d5b887185865").toVector
      Hkdf(salt, ikm, info, 42).toVector shouldBe Hkdf.expand(prk, info, 42).toVector
    }
  }
}
