package naogateway.sim.gs1500m

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

class OverflowExperimentSpec extends AnyWordSpec with Matchers {
  import OverflowExperiment.{Config, ThesisFirmware, runPath, schedule}

  private def experiment(config: Config = Config()): OverflowExperiment.Result = OverflowExperiment.run(config)

  private val ms = 1000000L

  "The thesis's overflow experiment over the raw link" should {
    val result = experiment()

    "sum far less than 4950, in the thesis's range of about 900 to 1000" in {
      info(result.toString)
      result.expectedSum shouldBe 4950
      result.sum should be < 2500L
      result.sum should (be >= 850L and be <= 1100L)
    }
    "lose or clobber most datagrams, and deliver the rest intact" in {
      result.sent shouldBe 100
      result.received.toLong + result.lost + result.overwritten shouldBe 100L
      result.intact shouldBe result.received
      result.spurious shouldBe 0
      result.lost should be > 0L
      result.overwritten should be > 0L
      result.peakBuffered should be <= 1400
    }
    "be deterministic for a seed and spread like repeated runs over seeds" in {
      experiment() shouldBe result
      val sums = (1L to 8L).map(seed => experiment(Config(seed = seed)).sum)
      all(sums) should (be > 0L and be < 2500L)
      sums.distinct.size should be > 1
    }
    "give the same figures at a time scale of 0.01" in {
      experiment(Config(timeScale = 0.01)) shouldBe result
    }
  }

  "The schedule" should {
    "number the datagrams 0 to 99 in byte 0, one every 50 ms" in {
      val plan = schedule(Config())
      plan.map(_.datagram.payload.head.toInt) shouldBe (0 until 100)
      plan.map(_.at) shouldBe (0 until 100).map(_ * 50 * ms)
      all(plan.map(_.datagram.payload.length)) shouldBe 1000
    }
    "tell when the firmware got each datagram, for composing with other layers" in {
      val path = runPath(Config())
      val plan = schedule(Config())
      path.received.foreach { r =>
        val sentAt = plan(r.bytes.head.toInt).at
        r.at should be > sentAt
        r.handledAt should be > r.at
      }
      path.received.map(_.at) shouldBe path.received.map(_.at).sorted
    }
  }

  "The model" should {
    "lose nothing when the datagrams come 500 ms apart" in {
      val slow = experiment(Config(spacingMillis = 500.0))
      slow.sum shouldBe 4950
      slow.received shouldBe 100
    }
    "lose nothing when the firmware keeps up with one datagram per 50 ms" in {
      val brisk = ThesisFirmware.copy(handlePerByteMillis = 0.0, otherWorkMaxMillis = 0.0)
      experiment(Config(firmware = brisk)).sum shouldBe 4950
    }
  }
}
