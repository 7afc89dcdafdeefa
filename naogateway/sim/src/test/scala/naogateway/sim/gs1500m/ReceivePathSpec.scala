package naogateway.sim.gs1500m

import scala.collection.immutable.ArraySeq

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.sim.gs1500m.FirmwareEvent._

class ReceivePathSpec extends AnyWordSpec with Matchers {

  private val ms = 1000000L
  private val peer = Some(Remote("10.0.0.2", 3838))
  private val quiet = Cm530Config(keepAlive = None)

  private def run(
      schedule: Seq[Scheduled],
      config: Cm530Config = quiet,
      until: Long = 1000 * ms,
      module: Gs1500mModule = Gs1500mModule()
  ): ReceivePath.Run =
    ReceivePath.run(schedule, module, Cm530Firmware(config), until)

  "The firmware loop" should {
    "get a datagram when its bytes have crossed the line at its next poll, and handle it in header + parse time" in {
      val data = ArraySeq.fill[Byte](100)(65)
      val r = run(Seq(Scheduled(3 * ms, AirDatagram(0, peer, data))))
      val serial = Gs1500mSerial.encode(SerialEvent.Data(0, peer, data)).toOption.get.length
      val got = r.received
      got.map(_.bytes) shouldBe Vector(data)
      // Polls at 0 and every 10 ms: the datagram is read at 10 ms.
      got.head.at shouldBe 10 * ms + Gs1500mConfig().lineNanos(serial)
      got.head.handledAt - got.head.at shouldBe Cm530Costs.Real.nanos(0.01 + 0.05 + 5.0)
      got.head.remote shouldBe peer
    }
    "spend 24.12 ms on a status line" in {
      val m = Gs1500mModule().statusLine("DISCONNECT 0", 1 * ms).module
      val r = run(Nil, module = m)
      val line = r.firmwareEvents.collect { case s: StatusReceived => s }
      line.map(_.text) shouldBe Vector("DISCONNECT 0")
      line.head.handledAt - line.head.at shouldBe Cm530Costs.Real.nanos(0.01 + 24.12)
    }
    "send a keep-alive every 200 ms, which goes on air and is acknowledged" in {
      val r = run(Nil, config = Cm530Config(), until = 999 * ms)
      val sent = r.firmwareEvents.collect { case s: Sent if s.keepAlive => s.at }
      sent.size shouldBe 5 // at about 0, 200, 400, 600 and 800 ms: five keep-alives per second (docs/protocol.md §2)
      sent.zip(sent.tail).foreach { case (a, b) => (b - a) shouldBe (200 * ms +- 1 * ms) }
      val aired = r.moduleEvents.collect { case ModuleEvent.OnAir(_, data, at) => (data, at) }
      aired.map(_._1) shouldBe Vector.fill(5)(KeepAlive.StatusFrame)
      aired.map(_._2).zip(sent).foreach { case (air, start) =>
        air - start shouldBe Cm530Costs.Real.serialSendNanos(24)
      }
      r.firmware.stats.replies shouldBe 5 // each read by the next poll
      r.firmware.stats.keepAlives shouldBe 5
    }
    "send packets the application queues" in {
      val firmware = Cm530Firmware(quiet).send(Outgoing(2, ArraySeq[Byte](0, 1, 2)))
      val r = ReceivePath.run(Nil, Gs1500mModule(), firmware, 100 * ms)
      r.moduleEvents.collect { case ModuleEvent.OnAir(cid, data, _) => (cid, data) } shouldBe
        Vector((2, ArraySeq[Byte](0, 1, 2)))
    }
    "replay identically for the same seeds" in {
      val config = OverflowExperiment.Config()
      // Compared as a Boolean: a failure message would print every byte of the run.
      (OverflowExperiment.runPath(config) == OverflowExperiment.runPath(config)) shouldBe true
    }
  }
}
