package naogateway.sim

import java.net.InetSocketAddress

import org.scalatest.LoneElement
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.sim.gs1500m.{Cm530Config, Cm530Costs, Gs1500mConfig}

class FaithfulLinkSpec extends AnyWordSpec with Matchers with LoneElement {
  import FaithfulLinkSpec._

  private val ms = 1000000L
  private val peer = new InetSocketAddress("127.0.0.1", 40000)

  private def fresh(timeScale: Double = 1.0): FaithfulLink =
    FaithfulLink(Gs1500mConfig(), Cm530Config(), timeScale, seed = 1L, now = 0L)

  // Like a driver with a perfect timer: wakes exactly at nextWakeUp, feeds the inputs at their times.
  private def drive(start: FaithfulLink, inputs: Seq[Input], until: Long): Run =
    driveBy(_.nextWakeUp)(start, inputs, until)

  // The same with the wake-ups `wakeUp` asks for; the run counts what came out later than modelled.
  private def driveBy(wakeUp: FaithfulLink => Option[Long])(
      start: FaithfulLink, inputs: Seq[Input], until: Long): Run = {
    var link = start
    val tx = Vector.newBuilder[FaithfulLink.Transmission]
    val dl = Vector.newBuilder[FaithfulLink.Delivery]
    var late = 0
    val states = Vector.newBuilder[Any]
    def take(step: FaithfulLink.Step, now: Long): Unit = {
      link = step.link
      tx ++= step.transmitted
      dl ++= step.delivered
      late += step.transmitted.count(_.at < now) + step.delivered.count(_.at < now)
    }
    def wakeUntil(t: Long): Unit = {
      var guard = 0
      while (wakeUp(link).exists(_ <= t) && guard < 100000) {
        guard += 1
        val at = wakeUp(link).get
        take(link.advance(at), at)
      }
    }
    inputs.sortBy(_.at).foreach { input =>
      wakeUntil(input.at)
      input match {
        case Arrive(at, bytes)   => take(link.arrive(bytes, peer, at), at)
        case Send(at, bytes, to) => take(link.send(bytes, to, at), at)
      }
      // The link as an input leaves it (deliveries as values: their bytes are arrays).
      states += ((link.module, link.cpu, link.queued, link.onLine,
        link.handling.map(d => (d.bytes.toVector, d.from, d.at))))
    }
    wakeUntil(until)
    Run(link, tx.result(), dl.result(), late, states.result())
  }

  private def payload(n: Int, first: Int): Array[Byte] =
    Array.tabulate[Byte](n)(i => if (i == 0) first.toByte else 'a'.toByte)

  "A faithful link" should {
    "need no wake-up while nothing is under way" in {
      fresh().nextWakeUp shouldBe None
      val run = drive(fresh(), Seq(Arrive(0, payload(50, 1))), 1000 * ms)
      run.delivered should have size 1
      run.link.nextWakeUp shouldBe None
    }

    "deliver a datagram with its sender once the CM-530 has read and handled it" in {
      val bytes = payload(100, 7)
      val run = drive(fresh(), Seq(Arrive(0, bytes)), 1000 * ms)
      val d = run.delivered.loneElement
      d.bytes shouldBe bytes
      d.from shouldBe Some(peer)
      // ESC 'y' 0 "127.0.0.1 40000" TAB "0100": 23 header bytes + 100 at 46080 bytes/s, then 5.05 ms of handling.
      val expected = math.ceil(123 * 1e9 / 46080).toLong + Cm530Costs.Real.nanos(5.05)
      d.at shouldBe expected +- (1 * ms)
      run.link.module.stats.readIntact shouldBe 1
    }

    "put a frame on air at its destination after the CM-530's encode and send costs" in {
      val frame = payload(200, 3)
      val run = drive(fresh(), Seq(Send(0, frame, peer)), 1000 * ms)
      val tx = run.transmitted.loneElement
      tx.bytes shouldBe frame
      tx.to shouldBe peer
      tx.at should be >= Cm530Costs.Real.encodeAndSendNanos(200)
      tx.at should be < Cm530Costs.Real.encodeAndSendNanos(200) + 2 * ms
      run.link.module.stats.onAir shouldBe 1
    }

    "keep every frame's destination, in order" in {
      val targets = (1 to 5).map(i => new InetSocketAddress("127.0.0.1", 41000 + i))
      val sends = targets.zipWithIndex.map { case (to, i) => Send(i.toLong * ms, payload(60, i), to) }
      val run = drive(fresh(), sends, 2000 * ms)
      run.transmitted.map(_.to) shouldBe targets.toVector
      run.transmitted.map(_.bytes.head.toInt) shouldBe (0 until 5).toVector
    }

    "lose or overwrite a burst of 1 kB datagrams, and deliver the same datagrams spaced out" in {
      val burst = (0 until 10).map(i => Arrive(i * 100000L, payload(1000, i)))
      val crowded = drive(fresh(), burst, 3000 * ms)
      val c = crowded.link.module.stats
      (c.lost + c.overwritten) should be > 0L
      crowded.delivered.count(d => d.bytes.length == 1000) should be < 10

      val spaced = (0 until 10).map(i => Arrive(i * 100L * ms, payload(1000, i)))
      val calm = drive(fresh(), spaced, 3000 * ms)
      calm.link.module.stats.lost shouldBe 0
      calm.link.module.stats.overwritten shouldBe 0
      calm.delivered.map(_.bytes.head.toInt) shouldBe (0 until 10).toVector
    }

    "show the same frames and deliveries at the same times whether woken at every step or only when one shows" in {
      val random = new scala.util.Random(5)
      // Calm traffic and bursts that overflow the module's buffer, inbound and outbound.
      val inputs = (0 until 400).map { i =>
        val at = i * 15L * ms + (if (i % 50 < 10) 0L else random.nextInt(40).toLong * ms)
        val bytes = payload(20 + random.nextInt(if (i % 50 < 10) 900 else 120), i)
        if (random.nextBoolean()) Arrive(at, bytes)
        else Send(at, bytes, new InetSocketAddress("127.0.0.1", 42000 + random.nextInt(3)))
      }
      val until = 30000 * ms
      val everyStep = driveBy(_.nextStepAt)(fresh(), inputs, until)
      val shown = driveBy(_.nextWakeUp)(fresh(), inputs, until)
      // A timer that fires late, by up to 7 ms.
      val late = driveBy(_.nextWakeUp.map(at => at + (at / 1000 % 8) * ms))(fresh(), inputs, until)
      def seen(run: Run) =
        (run.transmitted.map(t => (t.bytes.toVector, t.to, t.at)),
          run.delivered.map(d => (d.bytes.toVector, d.from, d.at)))
      everyStep.transmitted.size should be > 100
      everyStep.delivered.size should be > 50
      (everyStep.link.module.stats.lost + everyStep.link.module.stats.overwritten) should be > 0L
      // Woken only when something shows, nothing shows late.
      (everyStep.late, shown.late) shouldBe ((0, 0))
      late.late should be > 0
      seen(shown) shouldBe seen(everyStep)
      seen(late) shouldBe seen(everyStep)
      // Every input finds the link as if it had been woken at every step.
      shown.states shouldBe everyStep.states
      late.states shouldBe everyStep.states
      def ended(run: Run) = run.link.advance(until + 1000 * ms).link
      ended(shown) shouldBe ended(everyStep)
      ended(late) shouldBe ended(everyStep)
      everyStep.link.nextStepAt shouldBe None
    }

    "scale every modelled duration with the time scale" in {
      val bytes = payload(500, 1)
      val real = drive(fresh(1.0), Seq(Arrive(0, bytes), Send(0, bytes, peer)), 1000 * ms)
      val fast = drive(fresh(0.05), Seq(Arrive(0, bytes), Send(0, bytes, peer)), 1000 * ms)
      fast.delivered.loneElement.at.toDouble shouldBe (real.delivered.loneElement.at * 0.05) +- 0.1 * ms
      fast.transmitted.loneElement.at.toDouble shouldBe (real.transmitted.loneElement.at * 0.05) +- 0.1 * ms
    }
  }
}

object FaithfulLinkSpec {
  private sealed trait Input { def at: Long }
  private final case class Arrive(at: Long, bytes: Array[Byte]) extends Input
  private final case class Send(at: Long, bytes: Array[Byte], to: InetSocketAddress) extends Input

  private final case class Run(
      link: FaithfulLink,
      transmitted: Vector[FaithfulLink.Transmission],
      delivered: Vector[FaithfulLink.Delivery],
      late: Int,
      states: Vector[Any]
  )
}
