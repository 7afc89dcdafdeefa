package naogateway.gateway

import java.net.{InetAddress, InetSocketAddress}

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.proto.Status
import naogateway.wire.MessageContents

/** The robot port reader's decision, without actors or sockets. */
class RoutingSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {
  // Two robots on hosts of their own; a robot sends from any port, so the port in `from` is only what its module used.
  private val hostOne = InetAddress.getByAddress(Array[Byte](127, 0, 0, 41))
  private val hostTwo = InetAddress.getByAddress(Array[Byte](127, 0, 0, 42))
  private val stranger = InetAddress.getByAddress(Array[Byte](127, 0, 0, 49))
  private def from(host: InetAddress, port: Int) = new InetSocketAddress(host, port)
  private def at(port: Int) = from(hostOne, port)
  private val one = Routing.Route(1, hostOne, "robot-1")
  private val two = Routing.Route(2, hostTwo, "robot-2")
  private val table = Routing.Table.of(Vector(one, two))

  private def keepAlive(robotId: Int): Array[Byte] =
    MessageContents.encodeFrame(MessageContents(robotId, status = Some(Status(teamID = Some(1))))).toOption.get

  "Routing.decide" must {
    "hand a frame from a robot's bound IP address, carrying its id, to that robot, whatever its source port" in {
      Seq(4001, 45165, 3838).foreach { port =>
        Routing.decide(table, keepAlive(1), at(port)) match {
          case Routing.ToRobot(route, _, contents, size) =>
            route shouldBe one
            contents.robotId shouldBe 1
            size shouldBe keepAlive(1).length
          case other => fail(s"not routed from port $port: $other")
        }
      }
    }
    "leave to the gateway what the table cannot place: unknown ids, ids claimed from another address, unknown senders" in {
      Routing.decide(table, keepAlive(9), at(4001)) shouldBe a[Routing.ToGateway]
      Routing.decide(table, keepAlive(2), at(4001)) shouldBe a[Routing.ToGateway]
      Routing.decide(table, keepAlive(1), from(stranger, 4001)) shouldBe a[Routing.ToGateway]
      Routing.decide(Routing.Table.empty, keepAlive(1), at(4001)) shouldBe a[Routing.ToGateway]
    }
    "route a stream segment by its sender's IP address alone" in {
      val segment = Array[Byte](3, 0, 'h', 'i')
      Routing.decide(table, segment, from(hostTwo, 4002)) shouldBe Routing.SegmentToRobot(two, segment)
      Routing.decide(table, segment, from(hostTwo, 51000)) shouldBe Routing.SegmentToRobot(two, segment)
      Routing.decide(table, segment, from(stranger, 4002)) shouldBe Routing.Rejected(Rejection.StreamFromUnknownAddress,
        "", None)
    }
    "refuse bad frames, GameController packets and unclassifiable bytes, naming the robot bound to the sender" in {
      val truncated = keepAlive(1).dropRight(1)
      Routing.decide(table, truncated, at(4001)) match {
        case Routing.Rejected(kind, _, route) =>
          kind shouldBe Rejection.LengthMismatch
          route shouldBe Some(one)
        case other => fail(s"not refused: $other")
      }
      Routing.decide(table, "RGme\u0000\u0000".getBytes("US-ASCII"), from(stranger, 4999)) shouldBe
        Routing.Rejected(Rejection.GameControllerOnRobotPort, "", None)
      Routing.decide(table, Array.emptyByteArray, from(hostTwo, 4002)) match {
        case Routing.Rejected(kind, _, route) =>
          kind shouldBe Rejection.Unclassifiable
          route shouldBe Some(two)
        case other => fail(s"not refused: $other")
      }
    }
    "decide for any bytes from any sender without throwing" in {
      forAll { (bytes: Array[Byte], port: Int) =>
        noException should be thrownBy Routing.decide(table, bytes,
          from(if ((port & 1) == 0) hostOne else stranger, 4000 + (port & 3)))
      }
    }
  }
}
