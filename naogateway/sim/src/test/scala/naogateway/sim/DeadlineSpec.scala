package naogateway.sim

import scala.concurrent.duration._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.sim.StreamPairSimulation
import naogateway.sim.StreamPairSimulation._
import naogateway.wire.stream.StreamSettings

import naogateway.wire.stream.StreamTestKit._

/** Deadlines, expiry and skip notices over a partitioned or lossy channel. */
class DeadlineSpec extends AnyWordSpec with Matchers {

  private def settingsFor(window: Int): StreamSettings =
    if (window == 1) StreamSettings.thesis else StreamSettings.selectiveRepeat(window)

  /** A to B is cut for the first second; payload 0 must arrive within 300 ms, payloads 1 to 3 have no deadline. */
  private def partitioned(window: Int, honour: Boolean, timeLimit: FiniteDuration): SimResult = {
    val settings = settingsFor(window)
    val aToB = LinkSettings(outages = Vector(Outage(0L, ms(1000))))
    val config = SimConfig(
      settings,
      settings.copy(honourSkipNotices = honour),
      aToB,
      LinkSettings.perfect,
      seed = 1L,
      timeLimit = timeLimit
    )
    val sends = Vector(
      ScheduledSend(Side.A, 0L, bytes("stale soon"), deadline = Some(ms(300))),
      ScheduledSend(Side.A, 0L, bytes("one")),
      ScheduledSend(Side.A, ms(100), bytes("two")),
      ScheduledSend(Side.A, ms(1500), bytes("three"))
    )
    StreamPairSimulation.run(config, sends)
  }

  "A payload with a deadline" should {
    for (window <- Seq(1, 20))
      s"be reported Expired at its deadline and never delivered, while later payloads get through (window $window)" in {
        val result = partitioned(window, honour = true, timeLimit = 30.seconds)
        result.completed shouldBe true
        result.a.expired shouldBe Vector(Expiry(0L, ms(300)))
        result.a.acknowledged shouldBe Vector(1L, 2L, 3L)
        result.b.delivered.map(text) shouldBe Vector("one", "two", "three")
        result.b.stats.skipped shouldBe 1
        all(result.b.deliveries.map(_.at)) should be > ms(1000)
      }

    for (window <- Seq(1, 20))
      s"hold up the stream at a receiver that does not honour skip notices (window $window)" in {
        val result = partitioned(window, honour = false, timeLimit = 10.seconds)
        result.completed shouldBe false
        result.a.expired shouldBe Vector(Expiry(0L, ms(300)))
        result.b.stats.skipped shouldBe 0
        result.b.delivered shouldBe empty
        result.a.acknowledged shouldBe empty
        result.b.finalState.lastInOrder shouldBe settingsFor(window).maxSeq
        // The sender keeps repeating its skip notice instead of the expired data.
        result.a.stats.pureAcksSent should be > 3L
      }

    for (window <- Seq(1, 20))
      s"end acknowledged or expired, delivered at most once and in order, over a bad link (window $window)" in {
        val payloads = (0 until 60).map(i => bytes(f"payload $i%02d"))
        val sends = payloads.zipWithIndex.map { case (p, i) =>
          val at = ms(20L * i)
          ScheduledSend(Side.A, at, p, deadline = if (i % 3 == 0) Some(at + ms(60)) else None)
        }
        val config = SimConfig.symmetric(settingsFor(window), LinkSettings.lossy(0.45), seed = 99L)
        val result = StreamPairSimulation.run(config, sends)
        result.completed shouldBe true
        val expiredIds = result.a.expired.map(_.id).toSet
        result.a.acknowledged.toSet ++ expiredIds shouldBe payloads.indices.map(_.toLong).toSet
        expiredIds should not be empty
        val deliveredTexts = result.b.delivered.map(text)
        val deliveredIds = deliveredTexts.map(_.drop("payload ".length).toInt)
        deliveredIds shouldBe deliveredIds.sorted
        deliveredIds.distinct shouldBe deliveredIds
        deliveredIds.toSet should contain allElementsOf result.a.acknowledged.map(_.toInt)
        deliveredIds should contain allElementsOf payloads.indices.filter(_ % 3 != 0)
        result.b.stats.skipped should be <= expiredIds.size.toLong
      }
  }
}
