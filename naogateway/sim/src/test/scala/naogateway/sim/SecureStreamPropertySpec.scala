package naogateway.sim

import scala.collection.mutable
import scala.concurrent.duration._

import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.sim.StreamPairSimulation
import naogateway.sim.StreamPairSimulation._
import naogateway.wire.stream.{SecureStream, StreamSettings}

import SecureStream._
import naogateway.wire.stream.StreamTestKit._

/** Properties over arbitrary datagrams and over random seeded channels. */
class SecureStreamPropertySpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {

  /** The receiving rules of a fresh endpoint (one that never sent anything), written out plainly. */
  private final class ReceiverModel(settings: StreamSettings) {
    private val n = settings.sequenceSpace
    private val w = settings.window
    private var last = settings.maxSeq
    private val buffer = mutable.Map.empty[Int, Vector[Byte]]
    val delivered = mutable.ArrayBuffer.empty[Vector[Byte]]

    private def mod(x: Int) = ((x % n) + n) % n

    private def drain(): Unit =
      while (buffer.contains(mod(last + 1))) {
        last = mod(last + 1)
        delivered += buffer.remove(last).get
      }

    def feed(d: Array[Byte]): Unit =
      if (d.length >= 2 && d.length <= 1400) {
        val seq = d(0) & 0xff
        val ack = d(1) & 0xff
        val forward = mod(ack - settings.maxSeq)
        val ackOk = forward == 0 || n - forward <= w
        val offset = mod(seq - last - 1)
        if (seq <= settings.maxSeq && ack <= settings.maxSeq && ackOk && offset < w) {
          if (d.length > 2) {
            if (!buffer.contains(seq)) buffer(seq) = d.toVector.drop(2)
            drain()
          } else if (settings.honourSkipNotices && offset == 0) {
            last = mod(last + 1)
            buffer.remove(last).foreach(delivered += _)
            drain()
          }
        }
      }
  }

  private val settingsGen: Gen[StreamSettings] = for {
    window <- Gen.oneOf(1, 2, 4, 20)
    maxSeq <- if (window == 1) Gen.oneOf(1, 20, 41) else Gen.choose(2 * window - 1, 41)
    honour <- Gen.oneOf(true, false)
  } yield StreamSettings(window = window, maxSeq = maxSeq, honourSkipNotices = honour)

  private val anyByte: Gen[Byte] = Gen.choose(Byte.MinValue, Byte.MaxValue)

  /** Mostly small numbers in the header so that many datagrams look plausible, plus plain noise. */
  private def datagramGen(maxSeq: Int): Gen[Array[Byte]] = Gen.frequency(
    3 -> (for {
      seq <- Gen.choose(0, maxSeq)
      ack <- Gen.choose(0, maxSeq)
      len <- Gen.frequency(3 -> Gen.choose(0, 8), 1 -> Gen.choose(9, 1400))
      body <- Gen.containerOfN[Array, Byte](len, anyByte)
    } yield Array(seq.toByte, ack.toByte) ++ body),
    1 -> Gen.choose(0, 1500).flatMap(len => Gen.containerOfN[Array, Byte](len, anyByte)),
    1 -> Gen.containerOfN[Array, Byte](2, anyByte)
  )

  "SecureStream.receive" should {
    "never throw, and deliver exactly what the receiving rules allow from what was fed in, nothing else" in {
      val cases = for {
        settings <- settingsGen
        count <- Gen.choose(1, 120)
        inputs <- Gen.listOfN(count, datagramGen(settings.maxSeq))
      } yield (settings, inputs)
      forAll(cases, minSuccessful(300)) { case (settings, inputs) =>
        val model = new ReceiverModel(settings)
        var state = SecureStream.initial(settings, 0L)
        val deliveredBySut = mutable.ArrayBuffer.empty[Vector[Byte]]
        val fedTails = inputs.map(_.toVector.drop(2)).toSet
        inputs.zipWithIndex.foreach { case (d, i) =>
          model.feed(d)
          val step = state.receive(d, i.toLong * 1000000L)
          state = step.state
          step.outputs.foreach {
            case Deliver(p) => deliveredBySut += p.toVector
            case Transmit(t) =>
              t.length shouldBe HeaderBytes
              all(t.toSeq.map(_ & 0xff)) should be <= settings.maxSeq
            case other => fail(s"a pure receiver produced $other")
          }
        }
        deliveredBySut.toVector shouldBe model.delivered.toVector
        all(deliveredBySut.map(fedTails.contains)) shouldBe true
        deliveredBySut.size.toLong shouldBe state.stats.delivered
      }
    }
  }

  "Idle ACKs (protocol.md 11.4)" should {
    "follow only answered data: at most one per quiet spell after it, none from a fresh or idle endpoint" in {
      val events: Gen[List[Either[Array[Byte], Int]]] = Gen.listOf(Gen.frequency(
          2 -> datagramGen(41).map(Left(_)),
          3 -> Gen.frequency(3 -> Gen.choose(0, 400), 1 -> Gen.choose(400, 700000)).map(Right(_))
        ))
      forAll(settingsGen, events, minSuccessful(300)) { (settings, script) =>
        var state = SecureStream.initial(settings, 0L)
        var now = 0L
        var lastSent = 0L
        var answeredSinceIdle = false
        def ticked(at: Long): Vector[Array[Byte]] = {
          val step = state.tick(at)
          state = step.state
          step.outputs.collect { case Transmit(d) => d }
        }
        script.foreach {
          case Left(d) =>
            val step = state.receive(d, now)
            state = step.state
            // A receiver that never sends data transmits only to answer data or an acted-on skip notice.
            if (step.outputs.exists(_.isInstanceOf[Transmit])) {
              answeredSinceIdle = true
              lastSent = now
            }
          case Right(ms) =>
            now += ms * 1000000L
            val sent = ticked(now)
            if (sent.nonEmpty) {
              answeredSinceIdle shouldBe true
              sent.map(_.length) shouldBe Vector(HeaderBytes)
              answeredSinceIdle = false
              lastSent = now
            }
        }
        // What is owed is paid when due, and then nothing more is ever sent.
        state.idleAckDue shouldBe answeredSinceIdle
        if (answeredSinceIdle) {
          state.nextTimerAt shouldBe Some(lastSent + settings.idleAckNanos)
          ticked(lastSent + settings.idleAckNanos).map(_.length) shouldBe Vector(HeaderBytes)
        }
        state.nextTimerAt shouldBe None
        ticked(now + 3600L * 1000000000L) shouldBe empty
      }
    }
  }

  "Lost-resend detection" should {
    "on a channel that keeps order and never duplicates, send the oldest segment again only when its copy was lost" in {
      val runs = for {
        seed <- Gen.choose(Long.MinValue, Long.MaxValue)
        window <- Gen.oneOf(2, 4, 20)
        count <- Gen.choose(5, 80)
        lossOut <- Gen.choose(0.0, 0.4)
        lossBack <- Gen.choose(0.0, 0.4)
      } yield (seed, window, count, lossOut, lossBack)
      var detections = 0L
      forAll(runs, minSuccessful(200)) { case (seed, window, count, lossOut, lossBack) =>
        val random = new java.util.SplittableRandom(seed)
        val settings = StreamSettings.selectiveRepeat(window)
        var a = SecureStream.initial(settings, 0L)
        var b = SecureStream.initial(settings, 0L)
        val toB = mutable.Queue.empty[Array[Byte]]
        val toA = mutable.Queue.empty[Array[Byte]]
        // The fate of the newest copy of each sequence number A sent: None while it is on its way.
        val lost = mutable.Map.empty[Int, Option[Boolean]]
        val got = mutable.ArrayBuffer.empty[String]
        var acked = 0
        var now = 0L
        def fromA(step: Step): Unit = {
          val before = a.stats.lostRetransmissions
          a = step.state
          val data = datagrams(step).filter(_.length > HeaderBytes)
          if (a.stats.lostRetransmissions > before) {
            detections += 1
            withClue(
              s"seed $seed window $window: resent seq ${data.head(0)} while its copy was ${lost(data.head(0))}: ") {
              lost(data.head(0).toInt) shouldBe Some(true)
            }
          }
          data.foreach(d => lost(d(0).toInt) = None)
          acked += acknowledged(step).size
          toB ++= datagrams(step)
        }
        def fromB(step: Step): Unit = {
          b = step.state
          got ++= delivered(step)
          toA ++= datagrams(step)
        }
        (0 until count).foreach(i => fromA(a.offer(s"p$i", i.toLong, now)))
        var steps = 0
        while (acked < count && steps < 100000) {
          steps += 1
          now += ms(1)
          val r = random.nextDouble()
          if (toB.nonEmpty && (r < 0.5 || toA.isEmpty)) {
            val d = toB.dequeue()
            val drop = random.nextDouble() < lossOut
            if (d.length > HeaderBytes) lost(d(0).toInt) = Some(drop)
            if (!drop) fromB(b.receive(d, now))
          } else if (toA.nonEmpty) {
            val d = toA.dequeue()
            if (random.nextDouble() >= lossBack) fromA(a.receive(d, now))
          } else {
            // Both directions are empty: only a timer can move things on.
            now = math.max(now, a.nextTimerAt.getOrElse(now))
            fromA(a.tick(now))
            b.nextTimerAt.filter(_ <= now).foreach(_ => fromB(b.tick(now)))
          }
        }
        acked shouldBe count
        got.toVector shouldBe (0 until count).map(i => s"p$i")
      }
      // The property must not hold only because the rule never fired.
      detections should be > 0L
    }
  }

  "A pair of endpoints over a seeded lossy channel" should {
    "deliver every payload exactly once and in order, in both directions, at window 1 and 20" in {
      val runs = for {
        seed <- Gen.choose(Long.MinValue, Long.MaxValue)
        window <- Gen.oneOf(1, 20)
        loss <- Gen.choose(0.0, 0.3)
        duplication <- Gen.choose(0.0, 0.1)
        reordering <- Gen.choose(0.0, 0.2)
        jitterMs <- Gen.choose(0, 3)
        countA <- Gen.choose(1, 40)
        countB <- Gen.choose(0, 40)
        sizes <- Gen.listOfN(countA + countB, Gen.frequency(4 -> Gen.choose(1, 64), 1 -> Gen.choose(65, 1398)))
        spacingMs <- Gen.oneOf(0, 1, 10)
      } yield (seed, window, loss, duplication, reordering, jitterMs, countA, countB, sizes, spacingMs)
      forAll(runs, minSuccessful(60)) {
        case (seed, window, loss, duplication, reordering, jitterMs, countA, countB, sizes, spacingMs) =>
          val settings = if (window == 1) StreamSettings.thesis else StreamSettings.selectiveRepeat(window)
          val link = LinkSettings(
            loss = loss,
            duplication = duplication,
            reordering = reordering,
            reorderDelay = 5.millis,
            jitter = jitterMs.millis
          )
          val random = new scala.util.Random(seed)
          val payloads = sizes.zipWithIndex.map { case (size, i) =>
            val p = new Array[Byte](size)
            random.nextBytes(p)
            p(0) = i.toByte
            p
          }
          val fromA = payloads.take(countA)
          val fromB = payloads.drop(countA)
          val sends =
            evenlySpaced(Side.A, fromA, 0L, spacingMs.millis) ++ evenlySpaced(Side.B, fromB, 0L, spacingMs.millis)
          val result = StreamPairSimulation.run(SimConfig.symmetric(settings, link, seed), sends)
          withClue(s"seed $seed window $window loss $loss: ") {
            result.completed shouldBe true
            result.b.delivered.map(_.toVector) shouldBe fromA.map(_.toVector)
            result.a.delivered.map(_.toVector) shouldBe fromB.map(_.toVector)
            result.a.acknowledged shouldBe (0L until countA.toLong)
            result.b.acknowledged shouldBe (countA.toLong until (countA + countB).toLong)
            result.a.expired shouldBe empty
          }
      }
    }

    "stay exact under heavy reordering and duplication at window 20, where numbers are reused every 42 segments" in {
      // Without the skip-notice rule (only the next number) a few percent of these runs skipped or duplicated data;
      // without the sequence-reuse rule seeds 1030, 1352 and 1906 delivered a late copy of an old segment as new.
      val settings = StreamSettings.selectiveRepeat(20)
      ((1L to 300L) ++ Seq(1030L, 1352L, 1906L)).foreach { seed =>
        val random = new scala.util.Random(seed)
        val link = LinkSettings(
          loss = random.nextDouble() * 0.3,
          duplication = 0.2,
          reordering = 0.3,
          reorderDelay = 8.millis,
          jitter = 3.millis
        )
        val payloads = (0 until 200).map { _ =>
          val p = new Array[Byte](1 + random.nextInt(40))
          random.nextBytes(p)
          p
        }
        val (fromA, fromB) = payloads.splitAt(120)
        val sends = evenlySpaced(Side.A, fromA, 0L, 1.millis) ++ evenlySpaced(Side.B, fromB)
        val result = StreamPairSimulation.run(SimConfig.symmetric(settings, link, seed), sends)
        def firstDifference(got: Vector[Array[Byte]], sent: Seq[Array[Byte]]): Option[Int] =
          (0 until math.max(got.size, sent.size)).find { i =>
            i >= got.size || i >= sent.size || !java.util.Arrays.equals(got(i), sent(i))
          }
        withClue(s"seed $seed: ") {
          result.completed shouldBe true
          firstDifference(result.b.delivered, fromA) shouldBe None
          firstDifference(result.a.delivered, fromB) shouldBe None
          result.a.stats.skipped + result.b.stats.skipped shouldBe 0
        }
      }
    }
  }
}
