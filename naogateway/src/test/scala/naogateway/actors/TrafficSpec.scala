package naogateway.actors

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalacheck.Gen
import org.scalatest.wordspec.AnyWordSpecLike
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway._
import naogateway.link.UdpLink
import naogateway.wire.gamecontroller.GameState

class TrafficSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing with ScalaCheckPropertyChecks {
  private val robot = new InetSocketAddress("127.0.0.1", 3838)

  "TrafficMeter" must {
    "admit sends only while every 1 s window stays within the limit" in {
      forAll(Gen.listOf(Gen.zip(Gen.choose(0L, 50000000L), Gen.choose(1, 1400)))) { steps =>
        val meter = new TrafficMeter(1000000000L)
        var now = 0L
        var admitted = Vector.empty[(Long, Int)]
        steps.foreach { case (gap, size) =>
          now += gap
          if (meter.fits(now, size, 5000)) { meter.record(now, size); admitted :+= now -> size }
          else meter.fitsAt(now, size, 5000) should be > now
        }
        admitted.foreach { case (t, _) =>
          admitted.filter { case (u, _) => u > t - 1000000000L && u <= t }.map(_._2).sum should be <= 5000
        }
      }
    }
  }

  "Outbox" must {
    "never exceed the budget in any 1 s window when asked for far more, and send safety first" in {
      val link = createTestProbe[UdpLink.Command]()
      val outbox = spawn(Outbox(link.ref, BudgetSettings(10000, 0, 0.8), competition = false))
      val payload = new Array[Byte](1000)
      // 60 kB of commands and debug traffic at once: six times the budget.
      (1 to 30).foreach(_ => outbox ! Outbox.Send(1, robot, payload, Priority.Debug))
      (1 to 30).foreach(_ => outbox ! Outbox.Send(1, robot, payload, Priority.Command))
      outbox ! Outbox.Send(1, robot, Array[Byte](1, 2, 3), Priority.Safety)
      val start = System.nanoTime()
      var arrivals = Vector.empty[(Long, Int)]
      while (System.nanoTime() - start < 3500.millis.toNanos) {
        link.receiveMessage(5.seconds) match {
          case UdpLink.Send(bytes, _) => arrivals :+= (System.nanoTime() - start) -> bytes.length
          case other                  => fail(s"unexpected $other")
        }
      }
      // The first 10 kB go at once; the safety datagram is never held back behind the queue.
      arrivals.take(11).map(_._2) should contain(3)
      // Arrival times at the probe lag the outbox's decisions by a varying delay on a loaded machine, so the
      // windows checked here are 250 ms shorter; the exact guarantee is the TrafficMeter property above.
      arrivals.foreach { case (t, _) =>
        arrivals.filter { case (u, _) => u > t - 750.millis.toNanos && u <= t }.map(_._2).sum should be <= 10003
      }
      // Throughput stays near the budget: about 10 kB in each second, not a trickle.
      arrivals.count(_._1 < 3.seconds.toNanos) should be >= 25
      // Commands go before debug traffic.
      val stats = createTestProbe[Outbox.TrafficStats]()
      outbox ! Outbox.GetStats(stats.ref)
      stats.receiveMessage().queued("command") shouldBe 0
    }
    "send nothing to robots while the game runs in competition mode, and say which rule" in {
      val link = createTestProbe[UdpLink.Command]()
      val outcomes = createTestProbe[Outbox.Outcome]()
      val outbox = spawn(Outbox(link.ref, BudgetSettings(125000, 0, 0.8), competition = true))
      outbox ! Outbox.GameStateChanged(GameState.Playing)
      outbox ! Outbox.Send(1, robot, Array[Byte](1), Priority.Safety, Some(outcomes.ref), 7)
      outcomes.expectMessage(Outbox.RefusedByRule(7, Outbox.NoSendingWhileGameRuns))
      link.expectNoMessage(200.millis)
      outbox ! Outbox.GameStateChanged(GameState.Finished)
      outbox ! Outbox.Send(1, robot, Array[Byte](1), Priority.Command, Some(outcomes.ref), 8)
      outcomes.expectMessage(Outbox.Accepted(8))
      link.expectMessageType[UdpLink.Send]
    }
  }
}

class RateLimitedLogSpec extends org.scalatest.wordspec.AnyWordSpec with org.scalatest.matchers.should.Matchers {
  "RateLimitedLog" should {
    "log the 1st, 10th, 100th ... occurrence and nothing in between" in {
      (1L to 100000L).filter(naogateway.RateLimitedLog.due) shouldBe Seq(1L, 10L, 100L, 1000L, 10000L, 100000L)
    }
  }
}
