package naogateway.sim.gs1500m

import scala.collection.immutable.ArraySeq

import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.sim.gs1500m.ModuleEvent._
import naogateway.sim.gs1500m.SerialEvent._

object Gs1500mModuleSpec {
  private sealed trait Op
  private final case class Arrive(size: Int) extends Op
  private final case class Send(size: Int, transfer: Long) extends Op
  private case object Read extends Op
  private case object Advance extends Op
}

class Gs1500mModuleSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {
  import Gs1500mModuleSpec._

  implicit override val generatorDrivenConfig: PropertyCheckConfiguration =
    PropertyCheckConfiguration(minSuccessful = 200)

  private val ms = 1000000L
  private val peer = Some(Remote("192.168.1.100", 3838))
  // Filler bytes 0x80..0xE3 are neither ESC, nor a line end, nor text, so a headerless tail is plain garbage.
  private def payload(n: Int, first: Int = 0): ArraySeq[Byte] =
    ArraySeq.tabulate[Byte](n)(i => if (i == 0) first.toByte else (0x80 + i % 100).toByte)
  private def datagram(n: Int, first: Int = 0): AirDatagram = AirDatagram(0, peer, payload(n, first))

  private def module(overwrite: Double = 0.5, seed: Long = 1L) =
    Gs1500mModule(Gs1500mConfig(overwriteProbability = overwrite), seed)

  "The serial line" should {
    "carry 46080 bytes per second at 460800 baud 8N1" in {
      val config = Gs1500mConfig()
      config.bytesPerSecond shouldBe 46080.0
      config.lineNanos(46080) shouldBe 1000000000L
      config.lineNanos(1) shouldBe 21702L // 21701.39 ns, rounded up
      Gs1500mConfig(timeScale = 0.01).lineNanos(46080) shouldBe 10000000L
    }
    "take a read of n serial bytes n / 46080 s, freeing the buffer evenly meanwhile" in {
      val m = module().arrive(datagram(1000), 0L).module
      val read = m.firmwareRead(1 * ms)
      val serial = read.bytes.length
      serial shouldBe 1000 + 3 + "192.168.1.100 3838".length + 1 + 4
      read.doneAt shouldBe 1 * ms + Gs1500mConfig().lineNanos(serial)
      (read.doneAt - 1 * ms).toDouble shouldBe (serial / 46080.0 * 1e9 +- 1.0)
      val half = (1 * ms + read.doneAt) / 2
      read.module.bufferedAt(1 * ms) shouldBe 1000
      read.module.bufferedAt(half) shouldBe (500 +- 1)
      read.module.bufferedAt(read.doneAt) shouldBe 0
    }
  }

  "A datagram that fits" should {
    "reach the CM-530 intact, behind its ESC y header" in {
      val d = datagram(1000, 42)
      val arrived = module().arrive(d, 0L)
      arrived.events shouldBe Vector(Buffered(0L, 0L, 1000))
      arrived.module.buffered shouldBe 1000
      val read = arrived.module.firmwareRead(5 * ms)
      read.bytes shouldBe Gs1500mSerial.encode(Data(0, peer, d.payload)).toOption.get
      SerialDecoder.empty.feed(read.bytes)._2 shouldBe Vector(Data(0, peer, d.payload))
      read.events should contain(ReadOut(0L, read.doneAt, intact = true))
      read.module.stats.readIntact shouldBe 1
    }
    "fit an empty buffer even at the full 1400 bytes" in {
      val step = module(overwrite = 0.0).arrive(datagram(1400), 0L)
      step.events shouldBe Vector(Buffered(0L, 0L, 1400))
      step.module.buffered shouldBe 1400
    }
    "fit beside others as long as there is room" in {
      val m = module(overwrite = 0.0).arrive(datagram(700), 0L).module.arrive(datagram(700, 1), 1L)
      m.events shouldBe Vector(Buffered(1L, 1L, 700))
      val firstBytes = SerialDecoder.empty.feed(m.module.firmwareRead(2L).bytes)._2.collect { case d: Data =>
        d.bytes.head.toInt
      }
      firstBytes shouldBe Vector(0, 1)
    }
  }

  "An overflowing datagram" should {
    "be lost when the module does not overwrite" in {
      val m = module(overwrite = 0.0).arrive(datagram(1000, 1), 0L).module
      val step = m.arrive(datagram(1000, 2), 50 * ms)
      step.events shouldBe Vector(Lost(1L, 50 * ms, LossReason.BufferFull))
      step.module.stats.lost shouldBe 1
      val got = SerialDecoder.empty.feed(step.module.firmwareRead(60 * ms).bytes)._2
      got shouldBe Vector(Data(0, peer, payload(1000, 1)))
    }
    "overwrite the beginning of the oldest unread datagram when the module overwrites" in {
      val m = module(overwrite = 1.0).arrive(datagram(1000, 1), 0L).module
      val step = m.arrive(datagram(1000, 2), 50 * ms)
      step.events shouldBe Vector(Overwritten(0L, 50 * ms, 600, 400), Buffered(1L, 50 * ms, 1000))
      step.module.buffered shouldBe 1400
      step.module.stats.overwritten shouldBe 1
      val read = step.module.firmwareRead(60 * ms)
      read.events should contain(ReadOut(0L, read.doneAt, intact = false))
      // The older datagram lost its header with its beginning: the firmware sees its tail as garbage.
      SerialDecoder.empty.feed(read.bytes)._2 shouldBe Vector(Garbage(400), Data(0, peer, payload(1000, 2)))
    }
    "wipe a datagram out completely when the overflow needs all of it" in {
      val m = module(overwrite = 1.0).arrive(datagram(400, 1), 0L).module.arrive(datagram(1000, 2), 1L).module
      val step = m.arrive(datagram(1000, 3), 2L)
      step.events.collect { case o: Overwritten => (o.id, o.bytes, o.remaining) } shouldBe
        Vector((0L, 400, 0), (1L, 600, 400))
      step.module.rxQueue.collect { case f: RxEntry.Frame => f.id } shouldBe Vector(1L, 2L)
      step.module.stats.overwritten shouldBe 2
    }
    "be lost even when overwriting, if only bytes already crossing the line stand in the way" in {
      val m = module(overwrite = 1.0).arrive(datagram(1000, 1), 0L).module
      val reading = m.firmwareRead(1 * ms).module
      reading.arrive(datagram(1000, 2), 2 * ms).events shouldBe Vector(Lost(1L, 2 * ms, LossReason.BufferFull))
    }
    "be lost or overwrite by a seeded coin of the configured odds" in {
      def outcomes(seed: Long, p: Double): Vector[String] = {
        val start = Gs1500mModule(Gs1500mConfig(overwriteProbability = p), seed).arrive(datagram(1000), 0L).module
        (1 to 400).foldLeft((start, Vector.empty[String])) { case ((m, acc), i) =>
          val step = m.arrive(datagram(1000, i), i.toLong * ms)
          val outcome = if (step.events.exists(_.isInstanceOf[Lost])) "lost" else "overwrite"
          (step.module, acc :+ outcome)
        }._2
      }
      outcomes(7L, 0.5) shouldBe outcomes(7L, 0.5)
      outcomes(7L, 0.5) should not be outcomes(8L, 0.5)
      outcomes(7L, 0.3).count(_ == "overwrite").toDouble / 400 shouldBe (0.3 +- 0.08)
      outcomes(7L, 0.0).distinct shouldBe Vector("lost")
      outcomes(7L, 1.0).distinct shouldBe Vector("overwrite")
    }
    "be lost as oversize when larger than the whole buffer" in {
      val step = module().arrive(datagram(1401), 0L)
      step.events shouldBe Vector(Lost(0L, 0L, LossReason.Oversize))
      step.module.stats.lostOversize shouldBe 1
    }
  }

  "Outgoing packets" should {
    "hold buffer space until their last byte has crossed the line, then go on air and be acknowledged" in {
      val data = payload(1000)
      val sent = module().firmwareSend(0, data, 0L, transferNanos = 0L)
      val lineTime = Gs1500mConfig().lineNanos(1007)
      sent.module.buffered shouldBe 1000
      sent.module.nextOnAirAt shouldBe Some(lineTime)
      sent.module.advance(lineTime - 1).events shouldBe empty
      val aired = sent.module.advance(lineTime)
      aired.events shouldBe Vector(OnAir(0, data, lineTime))
      aired.module.buffered shouldBe 0
      SerialDecoder.empty.feed(aired.module.firmwareRead(lineTime).bytes)._2 shouldBe Vector(Ack)
    }
    "take the CM-530's slower send time when it is given" in {
      val slow = Cm530Costs.Real.serialSendNanos(24)
      val aired = module().firmwareSend(0, payload(24), 0L, slow).module.advance(1000 * ms)
      aired.events shouldBe Vector(OnAir(0, payload(24), slow))
    }
    "crowd out incoming datagrams, since both share the buffer" in {
      val sending = module(overwrite = 0.0).firmwareSend(0, payload(1000), 0L).module
      sending.arrive(datagram(1000), 1 * ms).events shouldBe Vector(Lost(0L, 1 * ms, LossReason.BufferFull))
      sending.arrive(datagram(400), 1 * ms).events shouldBe Vector(Buffered(0L, 1 * ms, 400))
    }
    "overwrite unread incoming data when they do not fit, or be lost when even that is not enough" in {
      val waiting = module().arrive(datagram(1000), 0L).module
      val sent = waiting.firmwareSend(0, payload(1000), 1 * ms)
      sent.events shouldBe Vector(Overwritten(0L, 1 * ms, 600, 400))
      val lost = sent.module.firmwareSend(0, payload(1000), 2 * ms)
      lost.events shouldBe Vector(SendLost(0, 1000, 2 * ms))
      lost.module.stats.sendsLost shouldBe 1
    }
    "refuse a bad connection number" in {
      module().firmwareSend(16, payload(1), 0L).events.head shouldBe a[Refused]
    }
  }

  "Status lines" should {
    "reach the CM-530 in order with the data" in {
      val m = module().arrive(datagram(10), 0L).module.statusLine("DISCONNECT 0", 1L).module
      SerialDecoder.empty.feed(m.firmwareRead(2L).bytes)._2 shouldBe
        Vector(Data(0, peer, payload(10)), StatusLine("DISCONNECT 0"))
    }
  }

  private val genOps: Gen[List[(Long, Op)]] = Gen.listOf(
    for {
      dt <- Gen.frequency(3 -> Gen.choose(0L, 2 * ms), 1 -> Gen.choose(0L, 100 * ms))
      op <- Gen.frequency(
        5 -> Gen.choose(0, 1500).map(Arrive(_)),
        2 -> Gen.zip(Gen.choose(0, 1400), Gen.choose(0L, 40 * ms)).map { case (n, t) => Send(n, t) },
        2 -> Gen.const(Read),
        1 -> Gen.const(Advance)
      )
    } yield (dt, op)
  )

  "Any sequence of inputs" should {
    "never hold more than 1400 bytes, and account for every datagram" in {
      forAll(genOps, Gen.choose(0.0, 1.0), Gen.choose(0L, 1000L)) { (ops, p, seed) =>
        val end = ops.foldLeft((Gs1500mModule(Gs1500mConfig(overwriteProbability = p), seed), 0L)) {
          case ((m, t0), (dt, op)) =>
            val t = t0 + dt
            val next = op match {
              case Arrive(n)         => m.arrive(AirDatagram(0, peer, payload(n)), t).module
              case Send(n, transfer) => m.firmwareSend(1, payload(n), t, transfer).module
              case Read              => m.firmwareRead(t).module
              case Advance           => m.advance(t).module
            }
            next.buffered should (be >= 0 and be <= 1400)
            (next, t)
        }._1
        val c = end.stats
        c.peakBuffered should be <= 1400
        c.arrived shouldBe c.buffered + c.lost
        c.overwritten should be <= c.buffered
        c.readIntact + c.readDamaged should be <= c.buffered
      }
    }
  }
}
