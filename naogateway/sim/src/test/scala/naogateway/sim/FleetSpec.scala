package naogateway.sim

import java.net.{InetSocketAddress, StandardProtocolFamily}
import java.nio.channels.DatagramChannel

import scala.concurrent.Await
import scala.concurrent.duration._
import scala.util.Try

import akka.Done
import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.testkit.TestLoopback

class FleetSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  private val somewhere = new InetSocketAddress("127.0.0.1", 11011)

  private def canBind(address: InetSocketAddress): Boolean =
    Try {
      val channel = DatagramChannel.open(StandardProtocolFamily.INET)
      try channel.bind(address)
      finally channel.close()
    }.isSuccess

  "A fleet's settings" should {
    "give distinct ids, a keeper first, the field roles in turn, distinct start poses and spread keep-alives" in {
      val robots = Fleet.robotSettings(FleetSettings.ofSize(8, somewhere).copy(teamId = 12))
      robots.map(_.firmware.robotId) shouldBe (1 to 8).toVector
      robots.map(_.firmware.role) shouldBe
        Vector("keeper", "striker", "defender", "supporter", "striker", "defender", "supporter", "striker")
      robots.map(_.firmware.teamId).distinct shouldBe Vector(12)
      robots.map(_.firmware.startPose).distinct.size shouldBe 8
      robots.foreach { r =>
        r.firmware.startPose.x should (be >= -4.5 and be < 0.0)
        math.abs(r.firmware.startPose.y) should be <= 3.0
        r.gateway shouldBe somewhere
        r.bindAddress.getPort shouldBe 0
        r.receivePort shouldBe 3838
      }
      // Each robot a host of its own, from 127.0.0.11 on: the gateway knows robots by IP address.
      robots.map(_.bindAddress.getAddress.getHostAddress) shouldBe (11 to 18).map(i => s"127.0.0.$i").toVector
      robots.map(_.keepAlivePhase) shouldBe (0 until 8).map(i => 200.millis * i.toLong / 8L).toVector
      robots.map(_.seed).distinct.size shouldBe 8
    }

    "take given ids and number the players within the GameController's 11 slots" in {
      val robots = Fleet.robotSettings(FleetSettings(somewhere, robotIds = Vector(40, 7, 23) ++ (100 until 110)))
      robots.map(_.firmware.robotId).take(3) shouldBe Vector(40, 7, 23)
      robots.head.firmware.role shouldBe "keeper"
      robots.map(_.firmware.playerNumber).max shouldBe 11
      an[IllegalArgumentException] should be thrownBy FleetSettings(somewhere, robotIds = Vector(1, 2, 1))
    }
  }

  "A fleet" should {
    "run 20 robots that send keep-alives with distinct ids from distinct addresses, power-cycle one, stop cleanly" in {
      val gateway = new TestGateway
      try {
        val fleet = Await.result(Fleet.start(system,
            FleetSettings.ofSize(20, gateway.address).copy(firstAddress = TestLoopback.block(20))), 30.seconds)
        fleet.robots.map(_._1) shouldBe (1 to 20).toVector
        fleet.robots.map(_._2).distinct.size shouldBe 20

        // Keep-alives until every robot has been heard, within a bounded time.
        var seen = Map.empty[Int, (InetSocketAddress, Option[String])]
        val deadline = 10.seconds.fromNow
        while (seen.size < 20 && deadline.hasTimeLeft()) {
          gateway.receive(deadline.timeLeft).foreach { heard =>
            heard.contents.filter(_.status.isDefined).foreach { c =>
              seen = seen.updated(c.robotId, heard.from -> c.status.flatMap(_.activeRole))
            }
          }
        }
        seen.keySet shouldBe (1 to 20).toSet
        // Heard from its own host (from its sending socket); it receives at that host's 3838.
        fleet.robots.foreach { case (id, address) =>
          seen(id)._1.getAddress shouldBe address.getAddress
          address.getPort shouldBe 3838
        }
        seen(1)._2 shouldBe Some("keeper")
        seen(2)._2 shouldBe Some("striker")

        Await.result(fleet.powerCycle(3, 1.second), 10.seconds) shouldBe Done
        val off = Await.result(fleet.state(3), 10.seconds)
        off.online shouldBe false
        off.bootId shouldBe 2
        Await.result(fleet.state(4), 10.seconds).online shouldBe true
        a[Exception] should be thrownBy Await.result(fleet.powerCycle(99, 1.second), 10.seconds)

        Await.result(fleet.stop(), 30.seconds) shouldBe Done
        // A closed port may stay taken until the socket layer has let go of it; a port never closed stays taken.
        eventually(timeout(15.seconds)) {
          fleet.robots.foreach { case (_, address) => canBind(address) shouldBe true }
        }
        gateway.drain()
        gateway.collectFor(500.millis) shouldBe empty
      } finally gateway.close()
    }

    "fail to start, and close what it opened, when a robot cannot bind its socket" in {
      val gateway = new TestGateway
      val first = TestLoopback.block(3)
      val settings = FleetSettings.ofSize(3, gateway.address).copy(firstAddress = first)
      // Robot 2's receive port is taken on its host.
      val taken =
        DatagramChannel.open(StandardProtocolFamily.INET).bind(new InetSocketAddress(settings.addressOf(1), 3838))
      try {
        val failure = Try(Await.result(Fleet.start(system, settings), 30.seconds)).failed.get
        failure.getMessage should include("robot 2")
        // The two robots that did start are stopped again: the keep-alives (five a second each) end for good.
        eventually(timeout(20.seconds), interval(100.millis)) {
          gateway.drain()
          gateway.collectFor(1.second) shouldBe empty
        }
      } finally {
        taken.close()
        gateway.close()
      }
    }
  }
}
