package naogateway.sim

import java.nio.ByteBuffer
import java.nio.charset.StandardCharsets

import scala.concurrent.duration._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.sim.StreamPairSimulation
import naogateway.sim.StreamPairSimulation._
import naogateway.wire.stream.StreamSettings

/** The thesis's acceptance tests (docs/protocol.md §11), over the seeded lossy channel. */
class ThesisAcceptanceSpec extends AnyWordSpec with Matchers {

  private val windows = Seq(1, 20)
  private val lossRates = Seq(0.0, 0.1, 0.2, 0.3)
  private val seeds = Seq(7L, 4242L)

  private def settingsFor(window: Int): StreamSettings =
    if (window == 1) StreamSettings.thesis else StreamSettings.selectiveRepeat(window)

  private val loremIpsum: String =
    ("Lorem ipsum dolor sit amet, consectetur adipiscing elit, sed do eiusmod tempor incididunt ut labore et " +
      "dolore magna aliqua. Ut enim ad minim veniam, quis nostrud exercitation ullamco laboris nisi ut aliquip ex " +
      "ea commodo consequat. Duis aute irure dolor in reprehenderit in voluptate velit esse cillum dolore eu fugiat " +
      "nulla pariatur. Excepteur sint occaecat cupidatat non proident, sunt in culpa qui officia deserunt mollit " +
      "anim id est laborum. ") * 6

  "Lorem Ipsum: one side sends a text in chunks" should {
    for (window <- windows; loss <- lossRates; seed <- seeds)
      s"arrive complete and in order at window $window with ${(loss * 100).toInt} % loss (seed $seed)" in {
        val random = new scala.util.Random(seed)
        val bytes = loremIpsum.getBytes(StandardCharsets.UTF_8)
        val chunks = Iterator
          .unfold(0) { at =>
            if (at >= bytes.length) None
            else {
              val size = 1 + random.nextInt(80)
              Some((bytes.slice(at, at + size), at + size))
            }
          }
          .toVector
        val config = SimConfig.symmetric(settingsFor(window), LinkSettings.lossy(loss), seed)
        val result = StreamPairSimulation.run(config, evenlySpaced(Side.A, chunks, 0L, 5.millis))
        result.completed shouldBe true
        new String(result.b.delivered.flatten.toArray, StandardCharsets.UTF_8) shouldBe loremIpsum
        result.b.stats.delivered shouldBe chunks.size
        if (loss > 0.0) result.a.stats.retransmissions should be > 0L
      }
  }

  /** One side of the "Mathe" test: its operations and, last, its own result and operand count. */
  private def matheMessages(seed: Long, operands: Int): (Vector[Array[Byte]], Long) = {
    val random = new java.util.SplittableRandom(seed)
    var own = 0L
    val ops = (0 until operands).map { i =>
      val x = 1 + random.nextInt(7)
      val op = if (i % 2 == 0) '+' else '*'
      own = if (op == '+') own + x else own * x
      Array[Byte]('O', op.toByte, x.toByte)
    }.toVector
    val last = ByteBuffer.allocate(13).put('R'.toByte).putLong(own).putInt(operands).array()
    (ops :+ last, own)
  }

  /** Applies the peer's operations to a copy; returns (copy, operands seen, the peer's claimed result and count). */
  private def replay(delivered: Vector[Array[Byte]]): (Long, Int, Option[(Long, Int)]) =
    delivered.foldLeft((0L, 0, Option.empty[(Long, Int)])) { case ((copy, count, claim), m) =>
      m(0).toChar match {
        case 'O' if m(1) == '+' => (copy + m(2), count + 1, claim)
        case 'O'                => (copy * m(2), count + 1, claim)
        case 'R' =>
          val b = ByteBuffer.wrap(m)
          b.get()
          (copy, count, Some((b.getLong(), b.getInt())))
        case other => fail(s"unexpected message type $other")
      }
    }

  "Mathe: both sides send operations at once" should {
    for (window <- windows; loss <- lossRates; seed <- seeds)
      s"agree on both results and operand counts at window $window with ${(loss * 100).toInt} % loss (seed $seed)" in {
        val operandsA = 60
        val operandsB = 45
        val (fromA, resultA) = matheMessages(seed * 31 + 1, operandsA)
        val (fromB, resultB) = matheMessages(seed * 31 + 2, operandsB)
        val sends = evenlySpaced(Side.A, fromA, 0L, 10.millis) ++ evenlySpaced(Side.B, fromB, 0L, 10.millis)
        val config = SimConfig.symmetric(settingsFor(window), LinkSettings.lossy(loss), seed)
        val result = StreamPairSimulation.run(config, sends)
        result.completed shouldBe true

        val (copyAtB, countAtB, claimOfA) = replay(result.b.delivered)
        claimOfA shouldBe Some((resultA, operandsA))
        copyAtB shouldBe resultA
        countAtB shouldBe operandsA

        val (copyAtA, countAtA, claimOfB) = replay(result.a.delivered)
        claimOfB shouldBe Some((resultB, operandsB))
        copyAtA shouldBe resultB
        countAtA shouldBe operandsB
      }
  }

  "The loss experiment: 100 datagrams of 1 kB every 50 ms" should {
    val datagrams = (1 to 100).map { i =>
      val d = Array.fill[Byte](1024)(0x55)
      d(0) = (i - 1).toByte
      d
    }
    for (window <- windows; loss <- lossRates; seed <- seeds)
      s"sum to 4950 at the receiver at window $window with ${(loss * 100).toInt} % loss (seed $seed)" in {
        val config = SimConfig.symmetric(settingsFor(window), LinkSettings.lossy(loss), seed)
        val result = StreamPairSimulation.run(config, evenlySpaced(Side.A, datagrams, 0L, 50.millis))
        result.completed shouldBe true
        result.b.delivered.map(_(0).toInt).sum shouldBe 4950
        result.b.delivered.size shouldBe 100
        if (loss > 0.0) result.a.link.lost should be > 0L
        if (seed == seeds.head && (loss == 0.0 || loss == 0.1))
          info(
            f"finished after ${result.finishedAt / 1e6}%.1f ms simulated, last delivery at " +
              f"${result.lastDeliveryAt / 1e6}%.1f ms, ${result.a.stats.dataSegmentsSent} data segments sent, " +
              f"${result.a.stats.retransmissions} retransmissions, ${result.a.link.lost} of " +
              f"${result.a.link.datagrams} datagrams A to B lost"
          )
      }
  }

  "Goodput under loss (the benchmark's measure)" should {
    "be higher at window 20 than at window 1 when 100 datagrams of 1 kB are queued at once" in {
      val datagrams = (1 to 100).map(i => Array.fill[Byte](1024)(i.toByte))
      def goodput(window: Int, loss: Double): Double = {
        val config = SimConfig.symmetric(settingsFor(window), LinkSettings.lossy(loss), seeds.head)
        val result = StreamPairSimulation.run(config, evenlySpaced(Side.A, datagrams))
        result.completed shouldBe true
        result.b.delivered.size shouldBe 100
        result.goodputBytesPerSecond
      }
      val w1 = goodput(1, 0.1) / goodput(1, 0.0)
      val w20 = goodput(20, 0.1) / goodput(20, 0.0)
      info(f"goodput at 10 %% loss relative to 0 %% loss: window 1 $w1%.2f, window 20 $w20%.2f")
      info(f"at 10 %% loss: window 1 ${goodput(1, 0.1) / 1e3}%.0f kB/s, window 20 ${goodput(20, 0.1) / 1e3}%.0f kB/s")
      goodput(20, 0.1) should be > goodput(1, 0.1) * 2
      w1 should (be > 0.0 and be < 1.0)
      w20 should (be > 0.0 and be < 1.0)
    }
  }
}
