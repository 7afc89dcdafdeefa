package naogateway.sim

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.sim.gs1500m.OverflowExperiment
import naogateway.wire.stream.StreamSettings

class StreamOverflowExperimentSpec extends AnyWordSpec with Matchers {
  import StreamOverflowExperiment.{Config, compare, run => runStream}

  private def withSeed(seed: Long, stream: StreamSettings = StreamSettings.thesis): Config =
    Config(experiment = OverflowExperiment.Config(seed = seed), stream = stream)

  "The overflow experiment through the module model" should {
    val default = compare()

    "sum far below 4950 raw, and exactly 4950 through the thesis stream, every payload once and in order" in {
      info(f"raw sum ${default.raw.sum}, stream sum ${default.stream.sum} in ${default.stream.seconds}%.2f s " +
        s"simulated, ${default.stream.retransmissions} retransmissions, ${default.stream.events} events")
      info(s"gateway ${default.stream.gateway}")
      info(s"robot ${default.stream.robot}")
      info(s"module ${default.stream.module}")
      default.raw.expectedSum shouldBe 4950
      default.raw.sum should be < 2500L
      default.stream.expectedSum shouldBe 4950
      default.stream.sum shouldBe 4950
      default.stream.inOrder shouldBe true
      default.stream.completed shouldBe true
      default.stream.robot.delivered shouldBe 100
      default.stream.gateway.acknowledged shouldBe 100
      default.stream.module.peakBuffered should be <= 1400
    }
    "pay for it in time: at window 1 every payload waits for a round trip through the firmware" in {
      // 100 payloads offered over 5 s, each needing ≥ 230 ms of reading and handling on the CM-530.
      default.stream.seconds should be > 100 * 0.2
      default.stream.lastDeliveryAt should be <= default.stream.finishedAt
    }
    "give the same for other seeds" in {
      for (seed <- Seq(2L, 3L, 7L, 42L)) withClue(s"seed $seed: ") {
        val c = compare(withSeed(seed))
        info(f"seed $seed: raw ${c.raw.sum}, stream ${c.stream.sum} in ${c.stream.seconds}%.2f s, " +
          s"${c.stream.retransmissions} retransmissions")
        c.raw.sum should be < 2500L
        c.stream.sum shouldBe 4950
        c.stream.inOrder shouldBe true
        c.stream.completed shouldBe true
      }
    }
    "deliver everything once and in order at a larger window too, where segments do overflow the buffer" in {
      val r = runStream(withSeed(1L, StreamSettings(window = 4, maxSeq = StreamSettings.ThesisMaxSeq)))
      info(f"window 4: sum ${r.sum} in ${r.seconds}%.2f s, ${r.retransmissions} retransmissions, " +
        s"module lost ${r.module.lost}, overwritten ${r.module.overwritten}")
      (r.module.lost + r.module.overwritten) should be > 0L
      r.retransmissions should be > 0L
      r.sum shouldBe 4950
      r.inOrder shouldBe true
      r.completed shouldBe true
    }
    "be deterministic for a seed" in {
      compare() shouldBe default
      runStream(withSeed(3L)) shouldBe runStream(withSeed(3L))
    }
    "stop at its limits and say so" in {
      val cut = runStream(Config(maxEvents = 50L))
      cut.completed shouldBe false
      cut.events shouldBe 50L
      cut.sum should be < 4950L
    }
  }
}
