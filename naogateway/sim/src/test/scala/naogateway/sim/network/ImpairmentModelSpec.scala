package naogateway.sim.network

import scala.concurrent.duration._

import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks
import naogateway.sim.SeededRandom

/** The settings, the generator and the pure decision function, without sockets. */
class ImpairmentModelSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {

  private def decisions(impairment: Impairment, rng: SeededRandom, n: Int): Vector[Decision] =
    Iterator
      .iterate((Option.empty[Decision], rng)) { case (_, r) =>
        val (d, next) = ImpairmentModel.decide(impairment, r)
        (Some(d), next)
      }
      .slice(1, n + 1)
      .flatMap(_._1)
      .toVector

  private val seeds = Gen.long
  private val probabilities = Gen.choose(0.0, 1.0)

  "Impairment" should {
    "accept probabilities in [0, 1] and non-negative delays" in {
      noException should be thrownBy Impairment(loss = 0.0, duplication = 1.0, reordering = 0.5, delay = 0.millis)
    }

    "reject probabilities outside [0, 1]" in {
      an[IllegalArgumentException] should be thrownBy Impairment(loss = -0.01)
      an[IllegalArgumentException] should be thrownBy Impairment(duplication = 1.01)
      an[IllegalArgumentException] should be thrownBy Impairment(reordering = Double.NaN)
    }

    "reject negative delays" in {
      an[IllegalArgumentException] should be thrownBy Impairment(delay = -1.milli)
      an[IllegalArgumentException] should be thrownBy Impairment(jitter = -1.nano)
      an[IllegalArgumentException] should be thrownBy Impairment(reorderMaxDelay = -5.millis)
    }
  }

  "SeededRandom" should {
    "draw doubles in [0, 1)" in {
      forAll(seeds) { seed =>
        val draws = Iterator.iterate(SeededRandom(seed).nextDouble)(_._2.nextDouble).take(200).map(_._1).toVector
        all(draws) should (be >= 0.0 and be < 1.0)
      }
    }

    "give each proxy and direction its own stream" in {
      val streams = for {
        proxy <- 0 until 5
        direction <- Direction.both
      } yield ImpairmentModel.stream(42L, proxy, direction).nextLong._1
      streams.distinct should have size 10
    }
  }

  "ImpairmentModel" should {
    "deliver exactly one immediate copy on a perfect link" in {
      forAll(seeds) { seed =>
        decisions(Impairment.Off, SeededRandom(seed), 100).distinct shouldBe
          Vector(Decision.Deliver(List(Duration.Zero), reordered = false))
      }
    }

    "lose datagrams at the configured rate" in {
      forAll(seeds, probabilities, minSuccessful(20)) { (seed, loss) =>
        val n = 10000
        val lost = decisions(Impairment(loss = loss), SeededRandom(seed), n).count(_ == Decision.Drop(DropCause.Loss))
        // The standard deviation of the rate is at most 0.005 here; 0.05 is ten of them.
        (lost.toDouble / n) shouldBe loss +- 0.05
      }
    }

    "never lose with probability 0 and always lose with probability 1" in {
      forAll(seeds) { seed =>
        decisions(Impairment(loss = 0.0), SeededRandom(seed), 500).count(_.isInstanceOf[Decision.Drop]) shouldBe 0
        decisions(Impairment(loss = 1.0), SeededRandom(seed), 500).distinct shouldBe Vector(
          Decision.Drop(DropCause.Loss))
      }
    }

    "send two copies when duplicating" in {
      forAll(seeds) { seed =>
        decisions(Impairment(duplication = 1.0, delay = 5.millis), SeededRandom(seed), 200).foreach {
          case d: Decision.Deliver =>
            d.duplicated shouldBe true
            d.delays shouldBe List(5.millis, 5.millis)
          case other => fail(s"expected two copies, got $other")
        }
      }
    }

    "duplicate at the configured rate" in {
      val n = 10000
      val duplicated = decisions(Impairment(duplication = 0.2), SeededRandom(7L), n).count {
        case d: Decision.Deliver => d.duplicated
        case _                   => false
      }
      (duplicated.toDouble / n) shouldBe 0.2 +- 0.05
    }

    "drop everything when partitioned, whatever the other settings" in {
      forAll(seeds, probabilities, probabilities) { (seed, loss, duplication) =>
        val settings = Impairment(loss = loss, duplication = duplication, partitioned = true)
        decisions(settings, SeededRandom(seed), 300).distinct shouldBe Vector(Decision.Drop(DropCause.Partition))
      }
    }

    "keep delays within base + jitter, plus at most the reorder delay when held back" in {
      val settings = Impairment(
        delay = 10.millis,
        jitter = 4.millis,
        reordering = 0.5,
        reorderMaxDelay = 30.millis,
        duplication = 0.5
      )
      val delivered = decisions(settings, SeededRandom(99L), 5000).collect { case d: Decision.Deliver => d }
      delivered should have size 5000
      delivered.foreach { d =>
        val upper = if (d.reordered) 10.millis + 4.millis + 30.millis else 10.millis + 4.millis
        val lower = if (d.reordered) 10.millis + 1.nano else 10.millis
        all(d.delays) should (be >= lower and be <= upper)
      }
      val heldBack = delivered.count(_.reordered).toDouble / delivered.size
      heldBack shouldBe 0.5 +- 0.05
    }

    "give the identical decision sequence for the same seed, and another for another seed" in {
      val settings = Impairment(loss = 0.3, duplication = 0.2, reordering = 0.3, jitter = 5.millis)
      forAll(seeds) { seed =>
        val first = decisions(settings, SeededRandom(seed), 300)
        val second = decisions(settings, SeededRandom(seed), 300)
        first shouldBe second
        decisions(settings, SeededRandom(seed + 1), 300) should not be first
      }
    }

    "consume the same randomness per datagram whatever the settings" in {
      forAll(seeds) { seed =>
        val afterPerfect = ImpairmentModel.decide(Impairment.Off, SeededRandom(seed))._2
        val afterPartition = ImpairmentModel.decide(Impairment(partitioned = true), SeededRandom(seed))._2
        val afterLoss = ImpairmentModel.decide(Impairment(loss = 1.0), SeededRandom(seed))._2
        afterPartition shouldBe afterPerfect
        afterLoss shouldBe afterPerfect
      }
    }
  }
}
