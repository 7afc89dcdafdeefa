package naogateway.sim.network

import java.net.{DatagramSocket, InetSocketAddress}
import java.nio.ByteBuffer

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.util.Random

import org.scalatest.concurrent.Eventually
import org.scalatest.matchers.should.Matchers
import org.scalatest.time.{Millis, Seconds, Span}
import org.scalatest.wordspec.AnyWordSpec

import naogateway.testkit.TestLoopback
import naogateway.sim.SeededRandom

/** The lossy network over real UDP on loopback. */
class LossyNetworkSpec extends AnyWordSpec with Matchers with Eventually {

  implicit override val patienceConfig: PatienceConfig =
    PatienceConfig(timeout = Span(10, Seconds), interval = Span(5, Millis))

  private def withNetwork[A](seed: Long)(body: LossyNetwork => A): A = {
    val network = LossyNetwork.start(seed)
    try body(network)
    finally network.stop()
  }

  private def withPeers[A](robots: Int)(body: (UdpPeer, IndexedSeq[UdpPeer]) => A): A = {
    val peers = new UdpPeer("gateway") +: (0 until robots).map(i => new UdpPeer(s"robot-$i", TestLoopback.robotAt()))
    try body(peers.head, peers.tail)
    finally peers.foreach(_.close())
  }

  private def withGatewayAndRobot[A](body: (UdpPeer, UdpPeer) => A): A =
    withPeers(1)((gateway, robots) => body(gateway, robots.head))

  private def numbered(i: Int, size: Int = 16): Array[Byte] = {
    val bytes = ByteBuffer.allocate(size).putInt(i).array()
    java.util.Arrays.fill(bytes, 4, size, i.toByte)
    bytes
  }

  private def numberOf(r: Received): Int = ByteBuffer.wrap(r.bytes.toArray).getInt

  // Bursts of ten with a pause let the receiving buffers drain even on a loaded machine.
  private def sendPaced(from: UdpPeer, to: InetSocketAddress, n: Int): Unit =
    (0 until n).foreach { i =>
      from.send(numbered(i), to)
      if (i % 10 == 9) Thread.sleep(2)
    }

  /** One datagram each way through `proxy`, checked byte for byte and by source address. */
  private def roundTrip(proxy: Proxy, robot: UdpPeer, gateway: UdpPeer, up: Array[Byte], down: Array[Byte]): Unit = {
    robot.send(up, proxy.clientSide)
    val atGateway = gateway.receive().getOrElse(fail("uplink datagram did not arrive"))
    atGateway.bytes shouldBe up.toVector
    atGateway.from shouldBe proxy.upstream
    gateway.send(down, proxy.receiveSide)
    val atRobot = robot.receive().getOrElse(fail("downlink datagram did not arrive"))
    atRobot.bytes shouldBe down.toVector
    atRobot.from shouldBe proxy.clientSide
  }

  private def canBind(address: InetSocketAddress): Boolean =
    try {
      new DatagramSocket(address).close()
      true
    } catch { case _: java.net.SocketException => false }

  "LossyNetwork" should {
    "forward every datagram byte-identical in both directions on a perfect link" in withNetwork(1L) { network =>
      withGatewayAndRobot { (gateway, robot) =>
        val proxy = network.addProxy(gateway.address, TestLoopback.address())
        proxy.clientSide.getAddress.isLoopbackAddress shouldBe true
        proxy.upstream.getAddress.isLoopbackAddress shouldBe true
        val random = new Random(5)
        (0 until 50).foreach { i =>
          val up = random.nextBytes(1 + random.nextInt(1400))
          val down = random.nextBytes(1 + random.nextInt(1400))
          withClue(s"round trip $i: ")(roundTrip(proxy, robot, gateway, up, down))
        }
        val stats = network.stats(proxy)
        stats.uplink shouldBe DirectionStats(received = 50, forwarded = 50)
        stats.downlink shouldBe DirectionStats(received = 50, forwarded = 50)
      }
    }

    "send replies to the robot given at creation before the robot has sent anything" in withNetwork(2L) { network =>
      withPeers(2) { (gateway, robots) =>
        val robot = robots(0)
        val other = robots(1)
        val known = network.addProxy(gateway.address, TestLoopback.address(), robot = Some(robot.address))
        gateway.send(numbered(7), known.receiveSide)
        val atRobot = robot.receive().getOrElse(fail("downlink datagram did not arrive"))
        atRobot.bytes shouldBe numbered(7).toVector
        atRobot.from shouldBe known.clientSide

        val unknown = network.addProxy(gateway.address, TestLoopback.address())
        gateway.send(numbered(8), unknown.receiveSide)
        eventually(network.stats(unknown).downlink.received shouldBe 1)
        network.stats(unknown).downlink shouldBe DirectionStats(received = 1, undeliverable = 1)

        // Without an address given, the robot's latest datagram decides: its IP at the receive port, not its source.
        other.send(numbered(9), unknown.clientSide)
        gateway.receive().map(_.from) shouldBe Some(unknown.upstream)
        gateway.send(numbered(10), unknown.receiveSide)
        other.receive().map(r => numberOf(r)) shouldBe Some(10)
      }
    }

    "deliver nothing the gateway sends to the robot's source port, and count it" in withNetwork(12L) { network =>
      withGatewayAndRobot { (gateway, robot) =>
        val proxy = network.addProxy(gateway.address, TestLoopback.address())
        robot.send(numbered(1), proxy.clientSide)
        val atGateway = gateway.receive().getOrElse(fail("uplink datagram did not arrive"))
        atGateway.from shouldBe proxy.upstream
        proxy.receiveSide shouldBe new InetSocketAddress(proxy.upstream.getAddress, TestLoopback.RobotReceivePort)
        // A reply to the datagram's source, as a gateway that ignored section 2 would send it.
        gateway.send(numbered(2), atGateway.from)
        eventually(network.stats(proxy).downlink.atSourcePort shouldBe 1)
        robot.receive(300.millis) shouldBe None
        network.stats(proxy).downlink shouldBe DirectionStats(atSourcePort = 1)
      }
    }

    "lose about 30 % of the uplink and account for every datagram" in withNetwork(3L) { network =>
      withGatewayAndRobot { (gateway, robot) =>
        val proxy = network.addProxy(gateway.address, TestLoopback.address(), uplink = Impairment(loss = 0.3))
        val n = 400
        sendPaced(robot, proxy.clientSide, n)
        eventually(network.stats(proxy).uplink.received shouldBe n)
        val uplink = network.stats(proxy).uplink
        uplink.received shouldBe uplink.forwarded + uplink.droppedLoss
        uplink.droppedPartition shouldBe 0
        uplink.forwarded.toDouble / n shouldBe 0.7 +- 0.1

        val arrived = gateway.receiveUpTo(uplink.forwarded.toInt, 10.seconds)
        arrived.size.toLong should be <= uplink.forwarded
        arrived.size.toDouble / n shouldBe 0.7 +- 0.15
        arrived.map(numberOf).distinct should have size arrived.size.toLong
        all(arrived.map(_.from)) shouldBe proxy.upstream
      }
    }

    "drop everything while partitioned and let traffic flow again afterwards" in withNetwork(4L) { network =>
      withGatewayAndRobot { (gateway, robot) =>
        val proxy = network.addProxy(gateway.address, TestLoopback.address())
        roundTrip(proxy, robot, gateway, numbered(1), numbered(2))

        network.partition(proxy, on = true)
        network.impairment(proxy, Direction.Uplink).partitioned shouldBe true
        network.impairment(proxy, Direction.Downlink).partitioned shouldBe true
        (0 until 10).foreach { i =>
          robot.send(numbered(i), proxy.clientSide)
          gateway.send(numbered(i), proxy.receiveSide)
        }
        eventually {
          val stats = network.stats(proxy)
          stats.uplink.received shouldBe 11
          stats.downlink.received shouldBe 11
        }
        gateway.collectFor(300.millis) shouldBe empty
        robot.collectFor(300.millis) shouldBe empty
        val stats = network.stats(proxy)
        stats.uplink.droppedPartition shouldBe 10
        stats.downlink.droppedPartition shouldBe 10

        network.partition(proxy, on = false)
        roundTrip(proxy, robot, gateway, numbered(3), numbered(4))
      }
    }

    "partition the whole network without touching each proxy's settings" in withNetwork(5L) { network =>
      withPeers(2) { (gateway, robots) =>
        val robotA = robots(0)
        val robotB = robots(1)
        val a = network.addProxy(gateway.address, TestLoopback.address())
        val b = network.addProxy(gateway.address, TestLoopback.address())
        network.partitionNetwork(on = true)
        robotA.send(numbered(1), a.clientSide)
        robotB.send(numbered(2), b.clientSide)
        eventually {
          network.stats(a).uplink.droppedPartition shouldBe 1
          network.stats(b).uplink.droppedPartition shouldBe 1
        }
        gateway.collectFor(300.millis) shouldBe empty
        network.impairment(a, Direction.Uplink).partitioned shouldBe false

        network.partitionNetwork(on = false)
        roundTrip(a, robotA, gateway, numbered(3), numbered(4))
        roundTrip(b, robotB, gateway, numbered(5), numbered(6))
      }
    }

    "apply changed settings to the next datagram" in withNetwork(6L) { network =>
      withGatewayAndRobot { (gateway, robot) =>
        val proxy = network.addProxy(gateway.address, TestLoopback.address())
        network.setImpairment(proxy, Direction.Downlink, Impairment(loss = 1.0))
        robot.send(numbered(1), proxy.clientSide)
        gateway.receive().map(numberOf) shouldBe Some(1)
        gateway.send(numbered(2), proxy.receiveSide)
        eventually(network.stats(proxy).downlink.droppedLoss shouldBe 1)
        robot.collectFor(200.millis) shouldBe empty

        network.setImpairment(proxy, Direction.Downlink, Impairment.Off)
        roundTrip(proxy, robot, gateway, numbered(3), numbered(4))
      }
    }

    "reorder datagrams when some are held back" in withNetwork(7L) { network =>
      withGatewayAndRobot { (gateway, robot) =>
        val held = Impairment(reordering = 0.5, reorderMaxDelay = 40.millis)
        val proxy = network.addProxy(gateway.address, TestLoopback.address(), uplink = held)
        val n = 200
        sendPaced(robot, proxy.clientSide, n)
        val order = gateway.receiveUpTo(n, 10.seconds).map(numberOf)
        order.size should be > n / 2
        order.distinct should have size order.size.toLong
        all(order) should (be >= 0 and be < n)
        order should not be order.sorted
        network.stats(proxy).uplink.reordered should be > 0L
      }
    }

    "send duplicated datagrams twice" in withNetwork(8L) { network =>
      withGatewayAndRobot { (gateway, robot) =>
        val proxy = network.addProxy(gateway.address, TestLoopback.address(), uplink = Impairment(duplication = 1.0))
        (0 until 20).foreach(i => robot.send(numbered(i), proxy.clientSide))
        val arrived = gateway.receiveUpTo(40, 10.seconds).map(numberOf)
        arrived.groupBy(identity).map { case (i, copies) => i -> copies.size } shouldBe (0 until 20).map(_ -> 2).toMap
        val uplink = network.stats(proxy).uplink
        uplink.forwarded shouldBe 20
        uplink.duplicated shouldBe 20
      }
    }

    "hold every datagram back for at least the base delay" in withNetwork(9L) { network =>
      withGatewayAndRobot { (gateway, robot) =>
        val proxy =
          network.addProxy(gateway.address, TestLoopback.address(), robot = Some(robot.address),
            downlink = Impairment(delay = 150.millis))
        val sent = System.nanoTime()
        gateway.send(numbered(1), proxy.receiveSide)
        robot.receive().map(numberOf) shouldBe Some(1)
        (System.nanoTime() - sent).nanos should be >= 150.millis
      }
    }

    "keep ten robots apart behind one gateway" in withNetwork(10L) { network =>
      withPeers(10) { (gateway, robots) =>
        val proxies = robots.map(_ => network.addProxy(gateway.address, TestLoopback.address()))
        robots.zip(proxies).zipWithIndex.foreach { case ((robot, proxy), i) =>
          robot.send(numbered(i), proxy.clientSide)
        }
        val arrived = gateway.receiveUpTo(10, 10.seconds)
        val expectedSources = proxies.zipWithIndex.map { case (p, i) => i -> p.upstream }.toMap
        arrived.map(r => numberOf(r) -> r.from).toMap shouldBe expectedSources
        // Replies to each robot's receive port: its IP as the gateway saw it, at 3838.
        arrived.foreach(r =>
          gateway.send(numbered(100 + numberOf(r)),
            new InetSocketAddress(r.from.getAddress, TestLoopback.RobotReceivePort)))
        robots.zipWithIndex.foreach { case (robot, i) => robot.receive().map(numberOf) shouldBe Some(100 + i) }
      }
    }

    "make the same decisions for the same seed and datagram sequence" in {
      val settings = Impairment(loss = 0.5, duplication = 0.3)
      val n = 40
      def run(seed: Long): Vector[(Long, Long)] = withNetwork(seed) { network =>
        withGatewayAndRobot { (gateway, robot) =>
          val proxy = network.addProxy(gateway.address, TestLoopback.address(), uplink = settings)
          (1 to n).map { i =>
            robot.send(numbered(i), proxy.clientSide)
            eventually(network.stats(proxy).uplink.received shouldBe i)
            val uplink = network.stats(proxy).uplink
            (uplink.forwarded, uplink.duplicated)
          }.toVector
        }
      }
      val expected = Iterator
        .iterate((0L, 0L, ImpairmentModel.stream(11L, 0, Direction.Uplink))) { case (forwarded, duplicated, rng) =>
          ImpairmentModel.decide(settings, rng) match {
            case (d: Decision.Deliver, next) => (forwarded + 1, duplicated + (if (d.duplicated) 1 else 0), next)
            case (_, next)                   => (forwarded, duplicated, next)
          }
        }
        .slice(1, n + 1)
        .map { case (f, d, _) => (f, d) }
        .toVector
      val first = run(11L)
      first shouldBe expected
      run(11L) shouldBe first
      run(12L) should not be first
    }

    "release its ports when a proxy is removed" in withNetwork(13L) { network =>
      withGatewayAndRobot { (gateway, robot) =>
        val proxy = network.addProxy(gateway.address, TestLoopback.address())
        roundTrip(proxy, robot, gateway, numbered(1), numbered(2))
        val last = network.removeProxy(proxy)
        last.uplink.forwarded shouldBe 1
        last.downlink.forwarded shouldBe 1
        // A closed port may stay taken until the socket layer has let go of it; a port never closed stays taken.
        eventually {
          canBind(proxy.clientSide) shouldBe true
          canBind(proxy.upstream) shouldBe true
        }
        an[IllegalArgumentException] should be thrownBy network.stats(proxy)
        an[IllegalArgumentException] should be thrownBy network.partition(proxy, on = true)
      }
    }

    "release every port and its thread on stop, and stop only once" in withNetwork(14L) { network =>
      val proxies = withGatewayAndRobot { (gateway, robot) =>
        val started = (0 until 3).map(_ =>
          network.addProxy(gateway.address, TestLoopback.address(), uplink = Impairment(delay = 1.second)))
        // A copy still waiting must not keep anything alive.
        robot.send(numbered(1), started.head.clientSide)
        eventually(network.stats(started.head).uplink.forwarded shouldBe 1)
        started
      }
      network.isRunning shouldBe true
      network.stop()
      network.stop()
      network.isRunning shouldBe false
      Thread.getAllStackTraces.keySet.asScala.filter(t => t.getName == network.name && t.isAlive) shouldBe empty
      eventually(all(proxies.flatMap(p => List(p.clientSide, p.upstream, p.receiveSide)).map(canBind)) shouldBe true)
      network.stats(proxies.head).uplink.forwarded shouldBe 1
      an[IllegalStateException] should be thrownBy network.addProxy(proxies.head.gateway, TestLoopback.address())
      an[IllegalStateException] should be thrownBy network.partitionNetwork(on = true)
    }
  }
}
