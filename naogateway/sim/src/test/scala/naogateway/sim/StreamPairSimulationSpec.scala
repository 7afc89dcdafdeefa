package naogateway.sim

import scala.concurrent.duration._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.wire.stream.StreamSettings

import StreamPairSimulation._

/** The simulation itself: determinism, channel statistics, rate limit and stopping. */
class StreamPairSimulationSpec extends AnyWordSpec with Matchers {

  private val payloads = (0 until 400).map(i => Array.fill[Byte](100)(i.toByte))

  private def summary(r: SimResult) =
    (
      r.finishedAt,
      r.lastDeliveryAt,
      r.events,
      r.a.stats,
      r.b.stats,
      r.a.link,
      r.b.link,
      r.b.deliveries.map(d => (d.at, d.payload.toVector))
    )

  "StreamPairSimulation" should {
    "give the same result for the same seed and a different one for another seed" in {
      val config = SimConfig.symmetric(StreamSettings.selectiveRepeat(8), LinkSettings.lossy(0.2), seed = 11L)
      val sends = evenlySpaced(Side.A, payloads, 0L, 1.millis)
      summary(StreamPairSimulation.run(config, sends)) shouldBe summary(StreamPairSimulation.run(config, sends))
      val other = StreamPairSimulation.run(config.copy(seed = 12L), sends)
      summary(other) should not be summary(StreamPairSimulation.run(config, sends))
    }

    "lose, duplicate and reorder about as often as configured" in {
      val link = LinkSettings(loss = 0.2, duplication = 0.1, reordering = 0.3, reorderDelay = 3.millis)
      val config = SimConfig.symmetric(StreamSettings.selectiveRepeat(20), link, seed = 21L)
      val result = StreamPairSimulation.run(config, evenlySpaced(Side.A, payloads, 0L, 1.millis))
      result.completed shouldBe true
      result.b.delivered.map(_.toVector) shouldBe payloads.map(_.toVector)
      val a = result.a.link
      a.lost.toDouble / a.datagrams shouldBe 0.2 +- 0.04
      a.duplicated.toDouble / (a.datagrams - a.lost) shouldBe 0.1 +- 0.03
      a.reordered.toDouble / (a.datagrams - a.lost + a.duplicated) shouldBe 0.3 +- 0.05
      result.b.stats.duplicatesDropped should be > 0L
    }

    "queue datagrams behind each other on a link with a limited rate" in {
      val slow = LinkSettings(baseDelay = Duration.Zero, bitsPerSecond = 80000L) // 1002 bytes take 100.2 ms
      val config = SimConfig(StreamSettings.selectiveRepeat(20), StreamSettings.selectiveRepeat(20), slow,
        LinkSettings.perfect, seed = 1L)
      val tenKilobytes = (0 until 10).map(_ => new Array[Byte](1000))
      val result = StreamPairSimulation.run(config, evenlySpaced(Side.A, tenKilobytes))
      result.b.deliveries.map(_.at) shouldBe (1 to 10).map(i => i * 100200000L)
    }

    "stop at the time limit and after maxEvents when payloads cannot get through" in {
      val cut = SimConfig(
        StreamSettings.thesis,
        StreamSettings.thesis,
        LinkSettings(outages = Vector(Outage(0L, Long.MaxValue))),
        LinkSettings.perfect,
        seed = 2L,
        timeLimit = 30.seconds
      )
      val sends = evenlySpaced(Side.A, payloads.take(3))
      val timed = StreamPairSimulation.run(cut, sends)
      timed.completed shouldBe false
      timed.finishedAt shouldBe 30.seconds.toNanos
      timed.b.delivered shouldBe empty
      // Only A's retransmissions happen here (B owes no idle ACK, protocol.md 11.4): about 20 in 30 s.
      val counted = StreamPairSimulation.run(cut.copy(maxEvents = 10L), sends)
      counted.completed shouldBe false
      counted.events shouldBe 10L
    }

    "record refused sends as settled, and finish at once without sends" in {
      val tiny = StreamSettings.thesis.copy(sendQueueLimit = 1)
      val config = SimConfig.symmetric(tiny, LinkSettings.perfect, seed = 3L)
      val result = StreamPairSimulation.run(config, evenlySpaced(Side.A, payloads.take(4)))
      result.completed shouldBe true
      result.a.refused.map(_.id) shouldBe Vector(2L, 3L)
      result.b.delivered.size shouldBe 2
      StreamPairSimulation.run(config, Vector.empty).events shouldBe 0L
    }
  }
}
