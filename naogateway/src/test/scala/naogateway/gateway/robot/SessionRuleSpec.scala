package naogateway.gateway.robot

import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

/** docs/protocol.md 6.2, docs/architecture.md 10: a restart is a consistent new session, never one odd keep-alive. */
class SessionRuleSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {

  implicit override val generatorDrivenConfig: PropertyCheckConfiguration =
    PropertyCheckConfiguration(minSuccessful = 300)

  /** The restarts a run of keep-alives makes, by the index of the keep-alive that completed each. */
  private def restarts(marks: Seq[SessionMark], keepAlives: Int): Vector[Int] =
    marks.zipWithIndex.foldLeft((SessionRule.empty, Vector.empty[Int])) { case ((rule, found), (mark, i)) =>
      val (next, restarted) = rule.step(mark, keepAlives)
      (next, if (restarted) found :+ i else found)
    }._2

  /** One session's keep-alives as the gateway receives them: sent every 150-250 ms from power-up time `bootAt` (gateway
    * clock), uptime counting from there, each delayed by 0-300 ms on the way. With or without bootId and clock.
    */
  private def session(
      bootId: Option[Int], bootAt: Long, firstUptime: Long, n: Int, clock: Boolean): Gen[Vector[SessionMark]] =
    for {
      gaps <- Gen.listOfN(n, Gen.choose(150L, 250L))
      delays <- Gen.listOfN(n, Gen.choose(0L, 300L))
    } yield {
      val uptimes = gaps.scanLeft(firstUptime)(_ + _).take(n).toVector
      uptimes.zip(delays).map { case (u, d) => SessionMark(bootId, if (clock) Some(u) else None, bootAt + u + d) }
    }

  private val bootIds: Gen[Option[Int]] = Gen.option(Gen.choose(0, 20))

  private val realSession: Gen[(Vector[SessionMark], Option[Int])] = for {
    bootId <- bootIds
    clock <- if (bootId.isEmpty) Gen.const(true) else Gen.oneOf(true, false)
    firstUptime <- Gen.choose(0L, 100000000L)
    n <- Gen.choose(1, 60)
    marks <- session(bootId, 5000000L, firstUptime, n, clock)
  } yield marks -> bootId

  /** Anything a stranger might put in a keep-alive, received at `at`. */
  private def forged(at: Long): Gen[SessionMark] =
    Gen.zip(bootIds, Gen.option(Gen.oneOf(Gen.choose(0L, 5000L), Gen.choose(0L, 1L << 33)))).map { case (b, u) =>
      SessionMark(b, u, at)
    }

  "The restart rule" should {
    "never see a restart in one session's keep-alives, delayed, reordered by neighbours, or lost" in {
      forAll(realSession, Gen.choose(1, 5), Gen.listOf(Gen.choose(0, 59))) { case ((marks, _), n, swaps) =>
        val reordered = swaps.foldLeft(marks) { (m, i) =>
          if (i + 1 < m.size) m.updated(i, m(i + 1)).updated(i + 1, m(i)) else m
        }
        restarts(reordered, n) shouldBe empty
      }
    }

    "never see a restart when runs of fewer than keep-alives forged keep-alives come between the robot's own" in {
      forAll(realSession, Gen.choose(2, 5)) { case ((marks, _), n) =>
        val runs = Gen.listOfN(marks.size, Gen.choose(0, n - 1).flatMap(k => Gen.listOfN(k, Gen.const(()))))
        forAll(runs, minSuccessful(1)) { gaps =>
          val mixed = marks.zip(gaps).flatMap { case (m, run) =>
            m +: run.map(_ => forged(m.receivedAtMillis).sample.get).toVector
          }
          restarts(mixed, n) shouldBe empty
        }
      }
    }

    "never see a restart in one odd keep-alive anywhere in a session" in {
      forAll(realSession, Gen.choose(1, 60), Gen.choose(2, 5)) { case ((marks, _), at, n) =>
        val i = math.min(at, marks.size)
        val odd = forged(marks(math.max(0, i - 1)).receivedAtMillis).sample.get
        restarts(marks.take(i) ++ (odd +: marks.drop(i)), n) shouldBe empty
      }
    }

    "see a real restart exactly once, at the keep-alives-th keep-alive of the new session" in {
      val restart = for {
        (before, bootId) <- realSession
        newBoot <- Gen.oneOf(bootId.map(_ + 1), None)
        n <- Gen.choose(1, 5)
        extra <- Gen.choose(0, 30)
        silence <- Gen.choose(0L, 10000L)
        // Another bootId, or (without one) an uptime starting again well below the old session's.
        firstUptime <- if (newBoot.isDefined) Gen.choose(0L, 5000L) else Gen.const(0L)
        after <- session(newBoot, before.last.receivedAtMillis + silence + 1L, firstUptime, n + extra, clock = true)
      } yield (before, after, n, newBoot)
      forAll(restart) { case (before, after, n, newBoot) =>
        // Without a new bootId only the uptime shows the restart: the old session must have had a clock and run > 2 s.
        whenever(newBoot.isDefined || before.last.uptimeMillis.exists(_ > 2000L)) {
          restarts(before ++ after, n) shouldBe Vector(before.size + n - 1)
        }
      }
    }

    "keep a session across the uptime's wrap after 49.7 days" in {
      val wrap = SessionRule.UptimeWrapMillis
      val marks =
        (0 until 20).map(i => SessionMark(Some(3), Some((wrap - 2000L + i * 200L) % wrap), 10000000L + i * 200L))
      restarts(marks, 3) shouldBe empty
    }

    "ignore keep-alives that say nothing about the session" in {
      val marks = Vector(SessionMark(Some(1), Some(1000L), 1000L)) ++
        (1 to 10).map(i => SessionMark(None, None, 1000L + i * 200L)) :+ SessionMark(Some(1), Some(3200L), 3200L)
      restarts(marks, 1) shouldBe empty
    }
  }
}
