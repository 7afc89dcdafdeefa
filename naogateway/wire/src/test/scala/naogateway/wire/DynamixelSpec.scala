package naogateway.wire

import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import com.google.protobuf.ByteString

import naogateway.proto.{BusBridge, BusResult}

/** Protocol 1.0 packets and the bus bridge's byte reassembly (docs/protocol.md 6.9), and the busBridge frame. */
class DynamixelSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {

  private def hex(s: String): Array[Byte] = s.split(" ").map(Integer.parseInt(_, 16).toByte)

  "a protocol 1.0 packet" should {
    "be framed and checksummed as the e-Manual's examples are" in {
      // Read 1 byte at 0x2B (present temperature) of id 1, and its status 0x20: the manual's worked example.
      Dynamixel.packet(1, Dynamixel.Read, Seq(0x2b, 1)) shouldBe hex("FF FF 01 04 02 2B 01 CC")
      Dynamixel.packet(1, 0, Seq(0x20)) shouldBe hex("FF FF 01 03 00 20 DB")
      Dynamixel.status(hex("FF FF 01 03 00 20 DB")) shouldBe Some(Dynamixel.Status(1, 0, Vector(0x20)))
    }
    "be refused with a wrong checksum, a wrong length or a missing header" in {
      Dynamixel.instruction(hex("FF FF 01 04 02 2B 01 CD")) shouldBe None
      Dynamixel.instruction(hex("FF FF 01 05 02 2B 01 CC")) shouldBe None
      Dynamixel.instruction(hex("FF 01 04 02 2B 01 CC")) shouldBe None
      Dynamixel.instruction(hex("FF FF 01 01 02 CC")) shouldBe None
    }
    "say how many status bytes are due" in {
      Dynamixel.statusBytesDue(Dynamixel.Instruction(1, Dynamixel.Read, Vector(36, 8))) shouldBe 14
      Dynamixel.statusBytesDue(Dynamixel.Instruction(1, Dynamixel.Ping, Vector.empty)) shouldBe 6
      Dynamixel.statusBytesDue(Dynamixel.Instruction(0xfe, Dynamixel.Write, Vector(24, 1))) shouldBe 0
      Dynamixel.statusBytesDue(Dynamixel.Instruction(1, Dynamixel.SyncWrite, Vector(30, 2, 1, 0, 2))) shouldBe 0
    }
  }

  "the reassembly" should {
    val ping = Dynamixel.packet(3, Dynamixel.Ping, Nil)
    val write = Dynamixel.packet(3, Dynamixel.Write, Seq(30, 0, 2))
    "skip bytes before FF FF and find packets split anywhere" in {
      val stream = hex("00 13 FF 7F") ++ ping ++ write
      (1 to stream.length - 1).foreach { cut =>
        val (r1, a) = Dynamixel.Reassembly().feed(stream.take(cut))
        val (r2, b) = r1.feed(stream.drop(cut))
        (a ++ b).map(_.toVector) shouldBe Vector(ping.toVector, write.toVector)
        r2.pending shouldBe empty
        r2.skipped shouldBe 4
        r2.dropped shouldBe 0
      }
    }
    "drop and count a packet with a bad checksum and carry on with the next" in {
      val bad = ping.updated(ping.length - 1, (ping.last + 1).toByte)
      val (r, out) = Dynamixel.Reassembly().feed(bad ++ write)
      out.map(_.toVector) shouldBe Vector(write.toVector)
      r.dropped shouldBe 1
    }
    "drop a packet longer than it takes, and never hold more than its capacity" in {
      val (r, out) = Dynamixel.Reassembly(maxPacketBytes = Dynamixel.MaxRequestBytes).feed(hex("FF FF 01 F0") ++ ping)
      out.map(_.toVector) shouldBe Vector(ping.toVector)
      r.dropped shouldBe 1
      forAll(Gen.listOf(Gen.choose(0, 255))) { noise =>
        val (next, _) = Dynamixel.Reassembly().feed(noise.map(_.toByte).toArray)
        next.pending.length should be <= Dynamixel.MaxPacketBytes
      }
    }
    "give back every packet of any stream of valid packets, whatever the chunks" in {
      val packets = Gen.listOf(for {
        id <- Gen.choose(0, 0xfe)
        instruction <- Gen.oneOf(1, 2, 3)
        params <- Gen.listOfN(3, Gen.choose(0, 255))
      } yield Dynamixel.packet(id, instruction, params).toVector)
      forAll(packets, Gen.choose(1, 20)) { (ps, chunk) =>
        val stream = ps.flatten.toArray
        val (_, out) = stream.grouped(chunk).foldLeft((Dynamixel.Reassembly(), Vector.empty[Vector[Byte]])) {
          case ((r, acc), bytes) =>
            val (next, found) = r.feed(bytes)
            (next, acc ++ found.map(_.toVector))
        }
        out shouldBe ps.toVector
      }
    }
  }

  "a busBridge frame" should {
    "carry a request and a reply through encoding and decoding" in {
      val request = BusBridge(7, request = Some(ByteString.copyFrom(Dynamixel.packet(1, Dynamixel.Ping, Nil))))
      BusBridgeFrame.decode(BusBridgeFrame.encode(2, request).get) shouldBe Some(2 -> request)
      val reply =
        BusBridge(7, reply = Some(ByteString.copyFrom(hex("FF FF 01 02 00 FC"))), result = Some(BusResult.BUS_OK))
      BusBridgeFrame.decode(BusBridgeFrame.encode(2, reply, HeaderForm.Compact).get) shouldBe Some(2 -> reply)
      MessageContents.decodeFrame(BusBridgeFrame.encode(2, reply).get).toOption.get._2.unknownExtensions shouldBe
        Vector(BusBridgeFrame.Field)
      BusBridgeFrame.mayCarry(BusBridgeFrame.encode(2, reply).get) shouldBe true
      BusBridgeFrame.mayCarry(MessageContents.encodeFrame(MessageContents(2)).toOption.get) shouldBe false
    }
  }
}
