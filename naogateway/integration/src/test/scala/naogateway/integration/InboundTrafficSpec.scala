package naogateway.integration

import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.testkit.TestLoopback

/** The outbox's received-traffic figure counts every datagram the robot port read, though it is told in batches. */
class InboundTrafficSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  "The robot port's reader" must {
    "tell the outbox every datagram it read, a batch's remainder as soon as the port falls quiet" in {
      val f = new GatewayFixture(testKit)
      val sender = DatagramChannel.open().bind(new InetSocketAddress(TestLoopback.address(), 0))
      try {
        val before = f.traffic()
        // 64 + 64 + 3: two whole batches and a remainder that only the port's quiet time can flush.
        val datagrams = 2 * naogateway.gateway.link.PortReader.InboundBatch + 3
        (1 to datagrams).foreach { _ =>
          sender.send(ByteBuffer.wrap(Array[Byte](1, 2, 3, 4, 5)), f.addresses.robots) // refused, but read and counted
        }
        createTestProbe[Unit]().awaitAssert((f.traffic().datagramsIn - before.datagramsIn) shouldBe datagrams.toLong,
          10.seconds)
      } finally {
        sender.close()
        f.stop()
      }
    }
  }
}
