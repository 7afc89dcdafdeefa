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
  private def drive(start: FaithfulLink, inputs: Seq[Input], until: Long): Run = {
    var link = start
    val tx = Vector.newBuilder[FaithfulLink.Transmission]
    val dl = Vector.newBuilder[FaithfulLink.Delivery]
    def take(step: FaithfulLink.Step): Unit = {
      link = step.link
      tx ++= step.transmitted
      dl ++= step.delivered
    }
    def wakeUntil(t: Long): Unit = {
      var guard = 0
      while (link.nextWakeUp.exists(_ <= t) && guard < 100000) {
        guard += 1
        take(link.advance(link.nextWakeUp.get))
      }
    }
    inputs.sortBy(_.at).foreach { input =>
      wakeUntil(input.at)
      input match {
        case Arrive(at, bytes)   => take(link.arrive(bytes, peer, at))
        case Send(at, bytes, to) => take(link.send(bytes, to, at))
      }
    }
    wakeUntil(until)
    Run(link, tx.result(), dl.result())
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
      delivered: Vector[FaithfulLink.Delivery]
  )
}
