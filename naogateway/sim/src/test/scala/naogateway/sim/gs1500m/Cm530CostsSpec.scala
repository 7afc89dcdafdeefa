package naogateway.sim.gs1500m

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.wire.{FumanoidsFrame, HeaderForm}

class Cm530CostsSpec extends AnyWordSpec with Matchers {
  import Cm530Costs._

  "The CM-530 cost model at scale 1.0" should {
    "cost about 88 ms in all for a 1400-byte message" in {
      encodeMillis(1400) shouldBe (53.23 +- 0.01)
      serialSendMillis(1400) shouldBe (34.48 +- 0.01)
      encodeAndSendMillis(1400) shouldBe (88.0 +- 0.5)
      Real.encodeAndSendNanos(1400) shouldBe (88000000L +- 500000L)
    }
    "agree with the thesis's combined fit 0.0632x - 0.6217 and the rounded coefficients of docs/simulator.md 1.4" in {
      for (x <- Seq(50, 250, 1000, 1400)) {
        encodeAndSendMillis(x) shouldBe ((0.0632 * x - 0.6217) +- 0.15)
        encodeMillis(x) shouldBe ((0.0386 * x - 0.81) +- 0.01)
        serialSendMillis(x) shouldBe ((0.0245 * x + 0.18) +- 0.01)
      }
    }
    "never charge a negative encoding time" in {
      encodeMillis(0) shouldBe 0.0
      encodeMillis(20) shouldBe 0.0
      encodeMillis(21) should be > 0.0
      Real.encodeNanos(1) shouldBe 0L
    }
    "charge the 24-byte keep-alive under a millisecond" in {
      KeepAlive().payload.length shouldBe 24
      FumanoidsFrame.decode(KeepAlive().payload.toArray).map(_.header.form) shouldBe Right(HeaderForm.Legacy)
      encodeAndSendMillis(24) shouldBe (0.89 +- 0.01)
    }
    "carry the thesis's receive-side figures" in {
      Real.statusLineNanos shouldBe 24120000L
      Real.parseNanos shouldBe 5000000L
      Real.emptyPollNanos shouldBe 10000L
      Real.messageHeaderNanos shouldBe 50000L
    }
  }

  "A time scale" should {
    "scale every simulated duration but keep the unscaled figures" in {
      val fast = Cm530Costs(0.01)
      fast.encodeAndSendNanos(1400) shouldBe (880000L +- 5000L)
      fast.statusLineNanos shouldBe 241200L
      fast.nanos(1.0) shouldBe 10000L
      encodeAndSendMillis(1400) shouldBe (88.0 +- 0.5)
    }
    "be positive" in {
      an[IllegalArgumentException] should be thrownBy Cm530Costs(0.0)
    }
  }
}
