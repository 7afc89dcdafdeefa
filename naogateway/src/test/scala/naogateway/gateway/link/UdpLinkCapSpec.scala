package naogateway.gateway.link

import java.net.{DatagramPacket, DatagramSocket, InetSocketAddress}

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.transport.RateLimitedLog
import naogateway.testkit.TestLoopback
import naogateway.gateway.link.UdpLink

/** The cap a UDP link puts on what it hands its owner: a flood on a port anyone can send to cannot grow a mailbox. */
class UdpLinkCapSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {
  import UdpLink._

  private val from = new InetSocketAddress("127.0.0.9", 4000)
  private val Second = RateWindow.SecondNanos

  "A rate window" should {
    "pass everything without a cap" in {
      val (w, passes, closed) = RateWindow.start(0L).offer(10L, 0, from)
      passes shouldBe true
      closed shouldBe None
      w shouldBe RateWindow.start(0L)
    }

    "pass the cap's number in a second, drop the rest, and tell the count once the second is over" in {
      val afterCap = (1 to 5).foldLeft(RateWindow.start(0L)) { (w, i) =>
        val (next, passes, closed) = w.offer(i.toLong, 3, from)
        passes shouldBe (i <= 3)
        closed shouldBe None
        next
      }
      afterCap.dropped shouldBe 2
      val (fresh, passes, closed) = afterCap.offer(Second + 1, 3, from)
      passes shouldBe true
      closed shouldBe Some(Dropped(2, from))
      fresh.passed shouldBe 1
      fresh.dropped shouldBe 0
      // A second with nothing dropped tells nothing.
      fresh.offer(3 * Second, 3, from)._3 shouldBe None
    }
  }

  "The rate-limited log" should {
    "log a count that grows by many when it passes a 1, 10, 100 ... mark" in {
      RateLimitedLog.dueBetween(0, 5) shouldBe true
      RateLimitedLog.dueBetween(2, 9) shouldBe false
      RateLimitedLog.dueBetween(9, 10) shouldBe true
      RateLimitedLog.dueBetween(11, 99) shouldBe false
      RateLimitedLog.dueBetween(99, 250) shouldBe true
      RateLimitedLog.dueBetween(250, 250) shouldBe false
    }
  }

  "A UDP link with a cap" should {
    "hand its owner at most the cap a second from a flood, and the count of the rest" in {
      val owner = createTestProbe[Event]()
      val address = TestLoopback.address()
      val link = spawn(UdpLink(new InetSocketAddress(address, 0), owner.ref, Options(maxDatagramsPerSecond = 20)))
      val local = owner.expectMessageType[Bound](5.seconds).local
      val sender = new DatagramSocket(new InetSocketAddress(address, 0))
      try {
        val flood = 2000
        (1 to flood).foreach(i => sender.send(new DatagramPacket(Array[Byte](i.toByte), 1, local)))
        // After the second, one more datagram closes the window and brings the count of the dropped ones.
        Thread.sleep(1100)
        sender.send(new DatagramPacket(Array[Byte](1), 1, local))
        val events = owner.receiveMessages(1, 5.seconds) ++ drain(owner)
        val received = events.count(_.isInstanceOf[Received])
        val dropped = events.collect { case Dropped(n, _, _) => n }.sum
        // The kernel may lose some of the flood itself; what arrived was either handed on (within the cap, plus the
        // one after the second) or counted.
        received should be <= 21 + 20 // the cap in the flood's second, in case the flood spanned two, and the last one
        received should be >= 2
        dropped should be > 0L
        (received + dropped) should be <= (flood + 1).toLong
      } finally {
        sender.close()
        link ! Unbind
      }
    }
  }

  "A UDP link with a cap and trusted addresses" should {
    "hand on every trusted datagram within its own cap, whatever a stranger floods, and mark its drops trusted" in {
      val owner = createTestProbe[Event]()
      val trustedAt = TestLoopback.address()
      val strangerAt = TestLoopback.address()
      val link = spawn(UdpLink(new InetSocketAddress(trustedAt, 0), owner.ref,
          Options(maxDatagramsPerSecond = 20, trusted = _ == trustedAt)))
      val local = owner.expectMessageType[Bound](5.seconds).local
      val trusted = new DatagramSocket(new InetSocketAddress(trustedAt, 0))
      val stranger = new DatagramSocket(new InetSocketAddress(strangerAt, 0))
      try {
        // 10 trusted datagrams, each after 200 of the stranger's: 2000 in all, a hundred times the cap.
        (1 to 10).foreach { i =>
          (1 to 200).foreach(_ => stranger.send(new DatagramPacket(Array[Byte](0), 1, local)))
          trusted.send(new DatagramPacket(Array[Byte](i.toByte), 1, local))
        }
        Thread.sleep(1100)
        stranger.send(new DatagramPacket(Array[Byte](0), 1, local))
        val events = owner.receiveMessages(1, 5.seconds) ++ drain(owner)
        events.collect { case Received(b, f) if f.getAddress == trustedAt => b.head.toInt } shouldBe (1 to 10)
        events.collect { case d: Dropped => d.trusted }.distinct shouldBe Seq(false)
        // Over its own cap, the trusted sender's datagrams are dropped too, and said to be trusted.
        (1 to 50).foreach(_ => trusted.send(new DatagramPacket(Array[Byte](1), 1, local)))
        Thread.sleep(1100)
        trusted.send(new DatagramPacket(Array[Byte](1), 1, local))
        (owner.receiveMessages(1, 5.seconds) ++ drain(owner)).collect { case d: Dropped => d.trusted } should
          contain(true)
      } finally {
        trusted.close()
        stranger.close()
        link ! Unbind
      }
    }
  }

  /** Every event the probe gets until it has been quiet for half a second. */
  private def drain(probe: akka.actor.testkit.typed.scaladsl.TestProbe[Event]): Seq[Event] =
    Iterator.continually(scala.util.Try(probe.receiveMessage(500.millis)).toOption).takeWhile(_.isDefined).flatten.toSeq
}
