package naogateway.gateway.robot

import scala.concurrent.duration._

import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.api.ClockEstimate

/** The clock estimate against generated robot clocks of known offset and drift, with random non-negative delays. */
class ClockSyncSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {

  implicit override val generatorDrivenConfig: PropertyCheckConfiguration =
    PropertyCheckConfiguration(minSuccessful = 60)

  /** A robot clock: reading r (whole ms, cut) at gateway time t is floor((t - off) * (1 + drift)). */
  private final case class Truth(offsetNanos: Long, driftPpm: Double) {
    private val rate = 1.0 + driftPpm * 1e-6
    def reading(gatewayNanos: Long): Long = math.floor((gatewayNanos - offsetNanos) / 1e6 * rate).toLong

    /** When the clock read `r` exactly, on the gateway's clock. */
    def gatewayNanosOf(r: Long): Double = offsetNanos + r / rate * 1e6
  }

  /** Delays in ms, drawn with a random source; every kind has values near 0 recurring (a LAN's jitter). */
  private sealed trait Delays { def draw(u: scala.util.Random): Double }
  private final case class Uniform(maxMs: Double) extends Delays {
    def draw(u: scala.util.Random) = u.nextDouble() * maxMs
  }
  private final case class Exponential(meanMs: Double) extends Delays {
    def draw(u: scala.util.Random) = -meanMs * math.log(1.0 - u.nextDouble())
  }
  private final case class Mixed(fastShare: Double, slowMs: Double) extends Delays {
    def draw(u: scala.util.Random) = if (u.nextDouble() < fastShare) u.nextDouble() * 2 else u.nextDouble() * slowMs
  }

  private val delays: Gen[Delays] = Gen.oneOf(
    Gen.choose(0.0, 20.0).map(Uniform.apply),
    Gen.choose(0.2, 5.0).map(Exponential.apply),
    Gen.zip(Gen.choose(0.2, 0.6), Gen.choose(10.0, 60.0)).map { case (f, s) => Mixed(f, s) }
  )

  private val truths: Gen[Truth] = for {
    offset <- Gen.choose(-3600000000000L, 3600000000000L)
    drift <- Gen.choose(-300.0, 300.0)
  } yield Truth(offset, drift)

  private final case class Run(truth: Truth, delays: Delays, loss: Double, seed: Long)

  private val runs: Gen[Run] = for {
    truth <- truths
    d <- delays
    loss <- Gen.choose(0.0, 0.3)
    seed <- Gen.long
  } yield Run(truth, d, loss, seed)

  /** Keep-alives every 200 ms for `seconds` (after a start well after the robot's power-up); the estimator after each.
    */
  private def play(
      run: Run, seconds: Int, start: ClockSync = ClockSync(), from: Option[Long] = None): Vector[(Long, ClockSync)] = {
    val u = new scala.util.Random(run.seed)
    val t0 = from.getOrElse(run.truth.offsetNanos + 5000000000L + u.nextInt(200) * 1000000L)
    Iterator.iterate(t0)(_ + 200000000L).take(seconds * 5).filter(_ => u.nextDouble() >= run.loss)
      .scanLeft(0L -> start) { case ((_, sync), t) =>
        val r = run.truth.reading(t)
        r -> sync.add(r, t + math.round(run.delays.draw(u) * 1e6))
      }.drop(1).toVector
  }

  /** The same 60 generated runs every time (seeds 1 to 60): the bound is statistical, so over fresh random runs a claim
    * that always holds would still fail now and then; the bench measures it over 50 robots of 10 minutes each.
    */
  private def fixed[T](gen: Gen[T], salt: Long): Vector[T] =
    (1L to 60L).map(i => gen.pureApply(Gen.Parameters.default, org.scalacheck.rng.Seed(i * 7919L + salt))).toVector
  private lazy val fixedRuns = fixed(runs, 0L)
  private lazy val fixedTruths = fixed(truths, 1L)

  private def errorMs(truth: Truth, e: ClockEstimate): Double =
    (e.gatewayNanos - truth.gatewayNanosOf(e.robotMillis)) / 1e6

  "ClockSync" should {

    "converge within its bound: offset and drift of a robot clock after a minute of keep-alives" in {
      val bounds = fixedRuns.map { run =>
        val (_, sync) = play(run, 90).last
        val e = sync.estimate.get
        math.abs(errorMs(run.truth, e)) should be <= e.errorBoundMillis
        e.driftPpm shouldBe run.truth.driftPpm +- 100.0
        sync.samples should be <= ClockSync.MaxSamples
        e.errorBoundMillis
      }.sorted
      // Useful as well as honest: small for most runs. Where the line's two touching points lie close together the
      // bound at the newest reading grows with the distance from them, so a few runs have a wide one.
      bounds(bounds.size / 2) should be < 5.0
      bounds(bounds.size * 9 / 10) should be < 25.0
      bounds.last should be < 60.0
    }

    "never claim a bound it does not meet, at any keep-alive, nor for readings around the newest" in {
      fixedRuns.foreach { run =>
        play(run, 120).foreach { case (r, sync) =>
          sync.estimate.foreach { e =>
            withClue(s"at reading $r with ${e.samples} samples: ") {
              math.abs(errorMs(run.truth, e)) should be <= e.errorBoundMillis
              val earlier = r - 2000
              math.abs(e.toGatewayNanos(earlier) - run.truth.gatewayNanosOf(earlier)) / 1e6 should be <= e.errorBoundAt(
                earlier)
            }
          }
        }
      }
    }

    "call its drift settled only within its drift bound, never in the first seconds, and most runs within a minute" in {
      val settledAfter = fixedRuns.map { run =>
        val steps = play(run, 90)
        steps.foreach { case (r, sync) =>
          sync.estimate.filter(_.driftSettled).foreach { e =>
            withClue(s"at reading $r with ${e.samples} samples: ") {
              e.driftPpm shouldBe run.truth.driftPpm +- e.driftBoundPpm
              e.driftBoundPpm should be <= ClockEstimate.SettledDriftPpm
            }
          }
        }
        // Right after a start the points span seconds: a fit over them says nothing about the crystal.
        steps.takeWhile { case (r, _) => r - steps.head._1 < 10000 }.flatMap(_._2.estimate).foreach(
          _.driftSettled shouldBe false)
        steps.collectFirst { case (r, sync) if sync.estimate.exists(_.driftSettled) => (r - steps.head._1) / 1000 }
      }
      settledAfter.count(_.exists(_ <= 60)) should be >= settledAfter.size / 2
    }

    "give no estimate before it has enough keep-alives" in {
      val run = Run(Truth(0L, 0.0), Uniform(5.0), 0.0, 1L)
      val steps = play(run, 10)
      steps.take(ClockSync.MinSamples - 1).foreach(_._2.estimate shouldBe None)
      steps(ClockSync.MinSamples - 1)._2.estimate should not be empty
    }

    "keep its memory bounded however fast keep-alives come" in {
      val sync = (0 until 5000).foldLeft(ClockSync()) { (s, i) =>
        s.add(i.toLong * 3, i * 3000000L + (i % 7) * 100000L)
      }
      sync.samples shouldBe ClockSync.MaxSamples
      sync.estimate should not be empty
    }

    "start a new session when the robot restarts or its clock goes back, and learn the new clock" in {
      fixedRuns.zip(fixedTruths).foreach { case (run, second) =>
        val first = play(run, 30).last._2
        first.estimate should not be empty
        val restarted = first.restart
        restarted.estimate shouldBe None
        restarted.samples shouldBe 0
        val after = play(run.copy(truth = second), 90, restarted).last._2.estimate.get
        math.abs(errorMs(second, after)) should be <= after.errorBoundMillis
        // Without being told: a reading more than a second below the newest is a new session too.
        val back = first.add(5L, 0L)
        back.samples shouldBe 1
        back.sessions shouldBe first.sessions + 1
      }
    }

    "set aside a point far below the line, and follow a clock that stepped" in {
      val run = Run(Truth(0L, 50.0), Uniform(10.0), 0.1, 7L)
      val steps = play(run, 60)
      val (r, sync) = steps.last
      val e = sync.estimate.get
      // A forged keep-alive claiming a reading 500 ms ahead: it would pull the line half a second.
      val forged = sync.add(r + 700, run.truth.gatewayNanosOf(r + 200).toLong)
      forged.outliers shouldBe sync.outliers + 1
      forged.estimate.get.gatewayNanos shouldBe e.gatewayNanos
      // The robot's clock itself jumps 500 ms ahead: after three such keep-alives the estimate follows.
      val stepped = Truth(run.truth.offsetNanos - 500000000L, 50.0)
      val after = play(run.copy(truth = stepped, seed = 8L), 30, sync,
        Some(run.truth.gatewayNanosOf(r).toLong + 200000000L)).last._2
      after.sessions shouldBe sync.sessions + 1
      math.abs(errorMs(stepped, after.estimate.get)) should be <= after.estimate.get.errorBoundMillis
    }

    "read a 32-bit uptime across its wrap as one clock" in {
      val wrap = 1L << 32
      val sync = ClockSync().add(wrap - 100, 0L)
      sync.unwrap32(50L) shouldBe wrap + 50
      sync.unwrap32(wrap - 90) shouldBe wrap - 90
      ClockSync().unwrap32(-1L) shouldBe wrap - 1
    }

    "estimate the offset of a clock alike the gateway's to within the reading's tick" in {
      val run = Run(Truth(123456789L, 0.0), Uniform(0.0), 0.0, 3L)
      val e = play(run, 30).last._2.estimate.get
      errorMs(run.truth, e) shouldBe 0.5 +- 0.5
      e.driftPpm shouldBe 0.0 +- 50.0
      ClockSyncSettings(30.seconds).window shouldBe 30.seconds
      an[IllegalArgumentException] should be thrownBy ClockSyncSettings(1.second)
    }
  }
}
