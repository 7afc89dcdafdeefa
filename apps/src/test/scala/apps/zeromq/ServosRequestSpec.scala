package apps.zeromq

import java.net.InetSocketAddress

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.wire.{MessageContents, RpcCall, RpcReply, RpcValue}
import naogateway.api.{LinkQuality, RobotSnapshot, ServoReading, ServoReadings}
import robotmiddleware.ServoLimits

/** `gateway.servos` (docs/zeromq.md 4): routed as a read of the gateway's own, answered with the ids of the hot and the
  * low-voltage servos by the middleware's limits, the telemetry itself in the reply's `servoTelemetry`.
  */
class ServosRequestSpec extends AnyWordSpec with Matchers {

  private val readings = ServoReadings(
    Vector(
      ServoReading(1, Some(512), Some(30), Some(12.1), Some(40)),
      ServoReading(2, Some(600), Some(-200), Some(9.6), Some(41)),
      ServoReading(3, Some(300), Some(0), Some(12.0), Some(66)),
      ServoReading(4, silent = true)
    ),
    Some(3L),
    0L
  )
  private val robot = RobotSnapshot(2, new InetSocketAddress("127.0.0.1", 3838), online = true,
    quality = LinkQuality.Good, servos = Some(readings))

  "gateway.servos" should {
    "route as the gateway's own read, without parameters" in {
      EndpointProtocol.route(EndpointRequest(2, RpcCall("gateway", "servos", Vector.empty))) shouldBe
        Right(Route.Servos(2))
      EndpointProtocol.route(EndpointRequest(2, RpcCall("gateway", "servos", Vector(RpcValue.UInt(1))))).left
        .getOrElse("") should startWith("malformed request: gateway.servos takes no parameters")
    }

    "answer the hot and the low-voltage servos' ids, and carry the telemetry as it travelled" in {
      val answer = RequestDesk.servos(robot, ServoLimits())
      answer.value shouldBe Some(RpcValue.Items(Vector(RpcValue.Items(Vector(RpcValue.UInt(3))),
            RpcValue.Items(Vector(RpcValue.UInt(2))))))
      val reply = MessageContents.parse(EndpointProtocol.reply(2, Some(9L), Right(answer))).toOption.get
      reply.servoTelemetry shouldBe Some(readings.toProto)
      reply.rpcResponse.map(RpcReply.fromProto).flatMap(_.callId) shouldBe Some(9L)
    }

    "answer empty lists and no telemetry before the robot's first" in {
      val answer = RequestDesk.servos(robot.copy(servos = None), ServoLimits())
      answer.value shouldBe Some(RpcValue.Items(Vector(RpcValue.Items(Vector.empty), RpcValue.Items(Vector.empty))))
      answer.servos shouldBe None
    }
  }
}
