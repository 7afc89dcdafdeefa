package naogateway.gateway

import java.net.{InetAddress, InetSocketAddress}

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

class RejectionLedgerSpec extends AnyWordSpec with Matchers {

  private def ip(n: Int): InetAddress = InetAddress.getByAddress(Array[Byte](10, 0, (n >> 8).toByte, n.toByte))

  "A rejection ledger" should {
    "count by kind, and by source only where the sender is known" in {
      val ledger = RejectionLedger()
        .count(Rejection.BadGzip, Some(ip(1)))
        .count(Rejection.BadGzip, Some(ip(1)), times = 4)
        .count(Rejection.UnknownCallId)
      ledger(Rejection.BadGzip) shouldBe 5
      ledger(Rejection.UnknownCallId) shouldBe 1
      ledger(Rejection.Replayed) shouldBe 0
      ledger.byKind shouldBe Map("bad gzip" -> 5L, "unknown call id" -> 1L)
      ledger.sources shouldBe Map("10.0.0.1" -> 5L)
    }

    "keep at most its bound of addresses, counting the rest together" in {
      val ledger =
        (1 to 200).foldLeft(RejectionLedger(maxSources = 8))((l, n) => l.count(Rejection.UnknownSender, Some(ip(n))))
      ledger.bySource.size shouldBe 8
      ledger.sources(RejectionLedger.OtherSources) shouldBe 192
      ledger.sources.values.sum shouldBe 200
      // A known address keeps its own counter after the bound is reached.
      ledger.count(Rejection.UnknownSender, Some(ip(1))).sources("10.0.0.1") shouldBe 2
    }

    "say a warning is due at the 1st, 10th, 100th of each kind, also when a count jumps past one" in {
      def dueAt(kind: Rejection, steps: Seq[Long]): Seq[Long] =
        steps.foldLeft((RejectionLedger(), Vector.empty[Long])) { case ((l, due), times) =>
          val next = l.count(kind, None, times)
          (next, if (next.warningDue(l, kind)) due :+ next(kind) else due)
        }._2
      dueAt(Rejection.BadProtobuf, Seq.fill(120)(1L)) shouldBe Seq(1L, 10L, 100L)
      dueAt(Rejection.GatewayBusy, Seq(5L, 20L, 3L)) shouldBe Seq(5L, 25L)
      val other = RejectionLedger().count(Rejection.BadGzip)
      other.warningDue(other, Rejection.BadGzip) shouldBe false
    }
  }

  "The shared ledger" should {
    "count every rejection of two threads at once" in {
      val shared = new RejectionLedger.Shared
      val from = new InetSocketAddress(ip(7), 4000)
      val threads = Vector.fill(2)(new Thread(() => (1 to 5000).foreach(_ => shared.count(Rejection.RobotBusy, from))))
      threads.foreach(_.start())
      threads.foreach(_.join())
      shared.current(Rejection.RobotBusy) shouldBe 10000
      shared.current.sources shouldBe Map("10.0.0.7" -> 10000L)
    }
  }
}
