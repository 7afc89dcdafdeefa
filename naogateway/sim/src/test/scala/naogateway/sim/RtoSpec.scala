package naogateway.sim

import scala.concurrent.duration._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.sim.StreamPairSimulation
import naogateway.sim.StreamPairSimulation._
import naogateway.wire.stream.{RtoEstimator, SecureStream, StreamSettings}

import naogateway.wire.stream.StreamTestKit._

/** The adaptive retransmission timeout: RFC 6298, bounds and Karn's rule. */
class RtoSpec extends AnyWordSpec with Matchers {

  private val thesis = StreamSettings.thesis

  private def steady(delay: FiniteDuration, jitter: FiniteDuration, settings: StreamSettings): SecureStream = {
    // Each payload is acknowledged before the next one is sent, so every sample is one clean round trip.
    val payloads = (0 until 60).map(i => bytes(s"sample $i"))
    val link = LinkSettings(baseDelay = delay, jitter = jitter)
    val config = SimConfig.symmetric(settings, link, seed = 5L)
    val result = StreamPairSimulation.run(config, evenlySpaced(Side.A, payloads, 0L, 3 * delay))
    result.completed shouldBe true
    if (jitter == Duration.Zero) result.a.stats.retransmissions shouldBe 0
    result.a.finalState
  }

  "RtoEstimator" should {
    "follow RFC 6298 for the first and later samples and back off up to maxRto" in {
      val first = RtoEstimator.initial(thesis).sample(ms(100), thesis)
      (first.srttNanos, first.rttvarNanos, first.rtoNanos) shouldBe ((ms(100), ms(50), ms(300)))
      val second = first.sample(ms(60), thesis)
      (second.srttNanos, second.rttvarNanos, second.rtoNanos) shouldBe ((ms(95), 47500000L, ms(285)))
      val backedOff = Iterator.iterate(second)(_.backedOff(thesis)).map(_.rtoNanos).take(5).toVector
      backedOff shouldBe Vector(ms(285), ms(570), ms(1140), ms(2000), ms(2000))
      RtoEstimator.initial(thesis).sample(ms(1), thesis).rtoNanos shouldBe ms(20)
    }

    "keep at most one doubling of the back-off after progress without a sample" in {
      val sampled = RtoEstimator.initial(thesis).sample(ms(100), thesis).sample(ms(60), thesis)
      val backedOff = sampled.backedOff(thesis).backedOff(thesis).backedOff(thesis)
      backedOff.rtoNanos shouldBe ms(2000)
      backedOff.afterProgress(thesis).rtoNanos shouldBe ms(570)
      sampled.backedOff(thesis).afterProgress(thesis).rtoNanos shouldBe ms(570)
      sampled.afterProgress(thesis).rtoNanos shouldBe ms(285)
      val unsampled = RtoEstimator.initial(thesis).backedOff(thesis).backedOff(thesis).backedOff(thesis)
      unsampled.rtoNanos shouldBe ms(1600)
      unsampled.afterProgress(thesis).rtoNanos shouldBe ms(400)
    }
  }

  "The retransmission timeout" should {
    "converge near the round-trip time of a steady link" in {
      val end = steady(50.millis, Duration.Zero, thesis)
      end.smoothedRttNanos.get shouldBe ms(100) +- ms(1)
      end.rtoNanos should (be >= ms(100) and be <= ms(103))
    }

    "stay a little above the round-trip time when the delay jitters" in {
      val end = steady(50.millis, 10.millis, StreamSettings.selectiveRepeat(20))
      end.smoothedRttNanos.get shouldBe ms(110) +- ms(6)
      end.rtoNanos should (be > end.smoothedRttNanos.get and be < ms(200))
    }

    "not go below minRto on a very fast link" in {
      steady(1.millis, Duration.Zero, thesis).rtoNanos shouldBe ms(20)
      steady(1.millis, Duration.Zero, thesis.copy(minRto = 50.millis)).rtoNanos shouldBe ms(50)
    }

    "back off to maxRto and no further when nothing gets through" in {
      for (maxRto <- Seq(2.seconds, 500.millis)) {
        val settings = thesis.copy(maxRto = maxRto)
        val config = SimConfig(
          settings,
          settings,
          LinkSettings(loss = 1.0),
          LinkSettings.perfect,
          seed = 3L,
          timeLimit = 20.seconds
        )
        val result = StreamPairSimulation.run(config, Vector(ScheduledSend(Side.A, 0L, bytes("lost"))))
        result.completed shouldBe false
        result.a.finalState.rtoNanos shouldBe maxRto.toNanos
        result.a.finalState.smoothedRttNanos shouldBe None
        result.a.stats.timeouts should be > 5L
      }
    }

    "take no sample from a retransmitted segment (Karn's rule) but from the next clean one" in {
      var a = SecureStream.initial(thesis, 0L)
      a = a.offer("x", 1L, 0L).state
      a = a.tick(ms(200)).state
      a.rtoNanos shouldBe ms(400)
      val lateAck = a.receive(segment(20, 0), ms(250))
      acknowledged(lateAck) shouldBe Vector(1L)
      lateAck.state.smoothedRttNanos shouldBe None
      lateAck.state.rtoNanos shouldBe ms(400)
      val clean = lateAck.state.offer("y", 2L, ms(250)).state.receive(segment(20, 1), ms(260))
      acknowledged(clean) shouldBe Vector(2L)
      clean.state.smoothedRttNanos shouldBe Some(ms(10))
      clean.state.rtoNanos shouldBe ms(30)
    }
  }
}
