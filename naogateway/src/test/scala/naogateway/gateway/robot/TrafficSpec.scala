package naogateway.gateway.robot

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalacheck.Gen
import org.scalatest.wordspec.AnyWordSpecLike
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.api.{Priority, TrafficStats}
import naogateway.gateway.BudgetSettings
import naogateway.gateway.link.UdpLink
import naogateway.wire.gamecontroller.GameState

class TrafficSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing
    with ScalaCheckPropertyChecks {
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

  /** A writer that hands every datagram to `link` as the send it is, and always takes it. */
  private def writer(link: akka.actor.typed.ActorRef[UdpLink.Command]): naogateway.transport.DatagramWriter =
    (bytes, to) => {
      link ! UdpLink.Send(bytes, to)
      true
    }

  "Outbox" must {
    "never let probes take more than budget.probe-share of the budget in any second, and not hold back commands" in {
      // The outbox's own decisions, against a clock this test moves: no timing of the machine is in the figures.
      val clock = new java.util.concurrent.atomic.AtomicLong(5000000000L)
      val written = new java.util.concurrent.ConcurrentLinkedQueue[(Long, Int, Byte)]()
      val recording: naogateway.transport.DatagramWriter =
        (bytes, _) => { written.add((clock.get, bytes.length, bytes(0))); true }
      val budget = BudgetSettings(20000, 0, 0.8, probeShare = 0.1)
      val outbox = spawn(Outbox(recording, budget, competition = false, clock = () => clock.get))
      val stats = createTestProbe[TrafficStats]()
      // Every message before it handled: the outbox answers in order.
      def settled(): Unit = { outbox ! Outbox.GetStats(stats.ref); stats.receiveMessage(10.seconds); () }
      val probe = Array.fill[Byte](50)(1)
      val command = Array.fill[Byte](500)(2)
      val start = clock.get
      // 300 probes from 30 robots at once (7.5 times the probes' share), then 20 commands.
      (1 to 300).foreach(i => outbox ! Outbox.Send(i % 30, robot, probe, Priority.Heartbeat))
      (1 to 20).foreach(i => outbox ! Outbox.Send(i % 30, robot, command, Priority.Command))
      settled()
      /* 2.6 s in steps of 10 ms, the outbox asked to drain at each (its own timer may drain in between: the same
       * clock). */
      (1 to 260).foreach { _ =>
        clock.addAndGet(10000000L)
        outbox ! Outbox.Drain
        settled()
      }
      import scala.jdk.CollectionConverters._
      val all = written.asScala.toVector
      val probes = all.filter(_._3 == 1)
      // The commands went out at once: the probes held back by their share do not stand in their way.
      all.filter(_._3 == 2).map(_._1 - start).max shouldBe 0L
      all.count(_._3 == 2) shouldBe 20
      // Any 1 s window holds at most 2000 bytes of probes (10 % of 20 000 B/s).
      probes.foreach { case (t, _, _) =>
        probes.filter { case (u, _, _) => u > t - 1000000000L && u <= t }.map(_._2).sum should be <= 2000
      }
      // And the probes did use their share: 40 at once, then about 40 a second.
      probes.size should be >= 100
      probes.size should be <= 120
    }
    "stay within the budget when asked for far more, send safety first and commands before debug" in {
      val link = createTestProbe[UdpLink.Command]()
      val outbox = spawn(Outbox(writer(link.ref), BudgetSettings(10000, 0, 0.8), competition = false))
      val debug = Array.fill[Byte](1000)(0)
      val command = Array.fill[Byte](1000)(1)
      val safety = Array[Byte](2, 2, 2)
      // Every decision of the outbox comes after this instant.
      val start = System.nanoTime()
      // 60 kB of commands and debug traffic at once: six times the budget.
      (1 to 30).foreach(_ => outbox ! Outbox.Send(1, robot, debug, Priority.Debug))
      (1 to 30).foreach(_ => outbox ! Outbox.Send(1, robot, command, Priority.Command))
      outbox ! Outbox.Send(1, robot, safety, Priority.Safety)
      // The first 10 debug datagrams, the safety one and every command; each may take a budget second to come.
      val arrivals = (1 to 41).map { _ =>
        link.receiveMessage(10.seconds) match {
          case UdpLink.Send(bytes, _) => (System.nanoTime() - start) -> bytes
          case other                  => fail(s"unexpected $other")
        }
      }.toVector
      // The first 10 kB go at once; the safety datagram is never held back behind the queue.
      arrivals.take(11).map(_._2.head) should contain(2.toByte)
      // The 1 s windows (0, 1 s], (1 s, 2 s], ... after `start` each hold at most 10 000 bytes of budgeted traffic,
      // and the safety datagram's 3 bytes may come on top once. A datagram is stamped here after the outbox sent it,
      // never before, so a late stamp can only make this bound looser, never break it.
      arrivals.foreach { case (t, _) =>
        val seconds = math.max(1L, (t + 999999999L) / 1000000000L)
        arrivals.filter(_._1 <= t).map(_._2.length).sum.toLong should be <= 3L + 10000L * seconds
      }
      // Commands go before debug traffic: after the first burst every datagram is a command.
      arrivals.drop(11).map(_._2.head) shouldBe Vector.fill(30)(1.toByte)
    }
    "send nothing to robots while the game runs in competition mode, and say which rule" in {
      val link = createTestProbe[UdpLink.Command]()
      val outcomes = createTestProbe[Outbox.Outcome]()
      val outbox = spawn(Outbox(writer(link.ref), BudgetSettings(125000, 0, 0.8), competition = true))
      outbox ! Outbox.GameStateChanged(GameState.Playing)
      outbox ! Outbox.Send(1, robot, Array[Byte](1), Priority.Safety, Some(outcomes.ref), 7)
      outcomes.expectMessage(Outbox.RefusedByRule(7, Outbox.NoSendingWhileGameRuns))
      link.expectNoMessage(200.millis)
      outbox ! Outbox.GameStateChanged(GameState.Finished)
      outbox ! Outbox.Send(1, robot, Array[Byte](1), Priority.Command, Some(outcomes.ref), 8)
      outcomes.expectMessage(Outbox.Accepted(8))
      link.expectMessageType[UdpLink.Send]
    }
    "count a datagram the socket did not take (kernel buffer full) as dropped, and keep sending" in {
      val taken = new java.util.concurrent.atomic.AtomicBoolean(false)
      val sent = new java.util.concurrent.atomic.AtomicInteger
      val full: naogateway.transport.DatagramWriter = (_, _) => { sent.incrementAndGet(); taken.get }
      val outbox = spawn(Outbox(full, BudgetSettings(125000, 0, 0.8), competition = false))
      val stats = createTestProbe[TrafficStats]()
      outbox ! Outbox.Send(1, robot, Array[Byte](1), Priority.Command)
      outbox ! Outbox.GetStats(stats.ref)
      stats.receiveMessage().dropped shouldBe 1
      taken.set(true)
      outbox ! Outbox.Send(1, robot, Array[Byte](1), Priority.Command)
      outbox ! Outbox.GetStats(stats.ref)
      val after = stats.receiveMessage()
      (after.dropped, after.datagramsOut, sent.get) shouldBe ((1L, 2L, 2))
    }
  }
}

class RateLimitedLogSpec extends org.scalatest.wordspec.AnyWordSpec with org.scalatest.matchers.should.Matchers {
  "RateLimitedLog" should {
    "log the 1st, 10th, 100th ... occurrence and nothing in between" in {
      (1L to 100000L).filter(naogateway.transport.RateLimitedLog.due) shouldBe Seq(1L, 10L, 100L, 1000L, 10000L,
        100000L)
    }
  }
}
