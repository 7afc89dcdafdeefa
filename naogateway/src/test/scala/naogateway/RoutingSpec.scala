package naogateway

import java.net.{InetAddress, InetSocketAddress}

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.proto.Status
import naogateway.wire.MessageContents

/** The robot port reader's decision, without actors or sockets. */
class RoutingSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {
  private def at(port: Int) = new InetSocketAddress(InetAddress.getLoopbackAddress, port)
  private val one = Routing.Route(1, at(4001), "robot-1")
  private val two = Routing.Route(2, at(4002), "robot-2")
  private val table = Routing.Table.of(Vector(one, two))

  private def keepAlive(robotId: Int): Array[Byte] =
    MessageContents.encodeFrame(MessageContents(robotId, status = Some(Status(teamID = Some(1))))).toOption.get

  "Routing.decide" must {
    "hand a frame from a robot's bound address, carrying its id, to that robot" in {
      Routing.decide(table, keepAlive(1), at(4001)) match {
        case Routing.ToRobot(route, _, contents, size) =>
          route shouldBe one
          contents.robotId shouldBe 1
          size shouldBe keepAlive(1).length
        case other => fail(s"not routed: $other")
      }
    }
    "leave to the gateway what the table cannot place: unknown ids, ids claimed from another address, unknown senders" in {
      Routing.decide(table, keepAlive(9), at(4001)) shouldBe a[Routing.ToGateway]
      Routing.decide(table, keepAlive(2), at(4001)) shouldBe a[Routing.ToGateway]
      Routing.decide(table, keepAlive(1), at(4999)) shouldBe a[Routing.ToGateway]
      Routing.decide(Routing.Table.empty, keepAlive(1), at(4001)) shouldBe a[Routing.ToGateway]
    }
    "route a stream segment by its sender's address alone" in {
      val segment = Array[Byte](3, 0, 'h', 'i')
      Routing.decide(table, segment, at(4002)) shouldBe Routing.SegmentToRobot(two, segment)
      Routing.decide(table, segment, at(4999)) shouldBe Routing.Refused("stream segment from an unknown address", None)
    }
    "refuse bad frames, GameController packets and unclassifiable bytes, naming the robot bound to the sender" in {
      val truncated = keepAlive(1).dropRight(1)
      Routing.decide(table, truncated, at(4001)) match {
        case Routing.Refused(reason, route) =>
          reason should startWith("bad frame: ")
          route shouldBe Some(one)
        case other => fail(s"not refused: $other")
      }
      Routing.decide(table, "RGme\u0000\u0000".getBytes("US-ASCII"), at(4999)) shouldBe
        Routing.Refused("GameController packet on the robot port", None)
      Routing.decide(table, Array.emptyByteArray, at(4002)) match {
        case Routing.Refused(reason, route) =>
          reason should startWith("unclassifiable: ")
          route shouldBe Some(two)
        case other => fail(s"not refused: $other")
      }
    }
    "decide for any bytes from any sender without throwing" in {
      forAll { (bytes: Array[Byte], port: Int) =>
        noException should be thrownBy Routing.decide(table, bytes, at(4000 + (port & 3)))
      }
    }
  }
}
