package naogateway.integration

import java.net.{InetAddress, InetSocketAddress}
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel
import java.util.concurrent.{LinkedBlockingQueue, TimeUnit}

import scala.jdk.CollectionConverters._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.gateway.link.{Backlog, RobotPort}

/** The robot port on loopback: its reader thread, its non-blocking writes, and a clean close. */
class RobotPortSpec extends AnyWordSpec with Matchers {
  private val loopback = new InetSocketAddress(InetAddress.getLoopbackAddress, 0)

  private final class Recorder extends RobotPort.Handler {
    val datagrams = new LinkedBlockingQueue[(Array[Byte], InetSocketAddress, String)]()
    def received(bytes: Array[Byte], from: InetSocketAddress): Unit =
      datagrams.put((bytes, from, Thread.currentThread().getName))
    def caughtUp(): Unit = ()
    def gameControllerReceived(bytes: Array[Byte], from: InetSocketAddress): Unit = ()
    def next(): (Array[Byte], InetSocketAddress, String) =
      Option(datagrams.poll(10, TimeUnit.SECONDS)).getOrElse(fail("no datagram within 10 s"))
  }

  private def readers(name: String): Int =
    Thread.getAllStackTraces.keySet.asScala.count(t => t.getName == name && t.isAlive)

  "A robot port" must {
    "hand each datagram, at its own size, with its sender, to the handler on its named reader thread" in {
      val port = RobotPort.open(loopback, 1 << 20, "robot-port-spec-reader")
      val peer = DatagramChannel.open().bind(loopback)
      try {
        val recorder = new Recorder
        port.start(recorder)
        peer.send(ByteBuffer.wrap(Array[Byte](1, 2, 3)), port.localAddress)
        peer.send(ByteBuffer.wrap(Array.fill[Byte](1400)(7)), port.localAddress)
        val (first, from, thread) = recorder.next()
        first.toVector shouldBe Vector[Byte](1, 2, 3)
        from shouldBe peer.getLocalAddress
        thread shouldBe "robot-port-spec-reader"
        recorder.next()._1.length shouldBe 1400
      } finally {
        peer.close()
        port.close()
      }
    }
    "write from any thread without a link actor, and refuse writes once closed" in {
      val port = RobotPort.open(loopback, 1 << 20, "robot-port-spec-writer")
      val peer = DatagramChannel.open().bind(loopback)
      try {
        port.start(new Recorder)
        port.send(Array[Byte](9, 8), peer.getLocalAddress.asInstanceOf[InetSocketAddress]) shouldBe true
        val in = ByteBuffer.allocate(16)
        peer.receive(in) shouldBe port.localAddress
        in.flip()
        in.remaining shouldBe 2
        port.close()
        port.send(Array[Byte](1), peer.getLocalAddress.asInstanceOf[InetSocketAddress]) shouldBe false
      } finally peer.close()
    }
    "stop its reader and free the port on close, however many are opened and closed" in {
      val name = "robot-port-spec-cycle"
      (1 to 20).foreach { _ =>
        val port = RobotPort.open(loopback, 1 << 16, name)
        port.start(new Recorder)
        port.readerAlive shouldBe true
        val bound = port.localAddress
        port.close()
        port.readerAlive shouldBe false
        // The same port can be bound again at once: the channel is closed, not left to the garbage collector.
        DatagramChannel.open().bind(bound).close()
      }
      readers(name) shouldBe 0
    }
  }

  "A backlog" must {
    "take places up to its limit, give them back as messages are handled, and never count below zero" in {
      val backlog = new Backlog(2)
      backlog.tryAdd() shouldBe true
      backlog.tryAdd() shouldBe true
      backlog.tryAdd() shouldBe false
      backlog.size shouldBe 2
      backlog.done()
      backlog.tryAdd() shouldBe true
      backlog.reset()
      backlog.done()
      backlog.size shouldBe 0
      backlog.add()
      backlog.size shouldBe 1
    }
  }
}
