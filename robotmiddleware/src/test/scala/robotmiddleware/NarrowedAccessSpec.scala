package robotmiddleware

import akka.actor.typed.ActorRef
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.access.{GatewayAccess, RobotAccess}

/** What the middleware's package can send the gateway and a robot, checked by the compiler (ScalaTest's compile-time
  * assertions typecheck each snippet here, outside package naogateway): the narrowed refs take exactly the middleware's
  * messages, and the gateway's internal messages cannot even be built.
  */
class NarrowedAccessSpec extends AnyWordSpec with Matchers {

  private val access: ActorRef[RobotAccess.Command] = null
  private val opened: RobotAccess.Opened = null
  private val gateway: ActorRef[GatewayAccess.Command] = null

  "The middleware's refs" should {
    "take the middleware's questions, Open, calls and camera registrations" in {
      assertCompiles("access ! RobotAccess.GetSnapshot(null)")
      assertCompiles("access ! RobotAccess.GetLinkStats(null)")
      assertCompiles("access ! RobotAccess.Open(null)")
      assertCompiles("opened.response ! RobotAccess.Call(null, null)")
      assertCompiles("opened.vision ! RobotAccess.RegisterVision(null, grid = false)")
      assertCompiles("gateway ! GatewayAccess.GetRobotAccess(1, null)")
      assertCompiles("gateway ! GatewayAccess.GetRobots(null)")
      assertCompiles("gateway ! GatewayAccess.Subscribe(null)")
    }
    "not take the whole robot actor's or the gateway's other messages" in {
      assertTypeError("access ! RobotActor.Connect(null)")
      assertTypeError("gateway ! Gateway.GetRobot(1, null)")
      assertTypeError("access ! RobotAccess.Call(null, null)")
      assertTypeError("opened.response ! RobotAccess.GetSnapshot(null)")
    }
    "hold no ref to the robot's sender, stream or heartbeat" in {
      assertTypeError("opened.noResponse")
      assertTypeError("opened.stream")
    }
  }

  "The gateway's internal messages" should {
    "not be built outside package naogateway" in {
      assertTypeError("RobotActor.FrameReceived(null, null, 0)")
      assertTypeError("RobotActor.SegmentReceived(null)")
      assertTypeError("RobotActor.DatagramRejected(null)")
      assertTypeError("RobotActor.Rebound(null)")
      assertTypeError("RobotActor.Subscribers(Set.empty)")
      assertTypeError("VisionActor.Subscribers(Map.empty)")
      assertTypeError("NoResponseActor.Finished(1L)")
      assertTypeError("ResponseActor.Reachability(true)")
      assertTypeError("Outbox.RobotGone(1)")
      assertTypeError("HeartBeatActor.ProbeNow")
      assertTypeError("StreamActor.Send(Array.emptyByteArray)")
      assertTypeError("naogateway.gateway.robot.RobotTestHooks.crashSender(null)")
      // The public protocol's wrappers are the gateway's own too: the middleware sends the access messages themselves.
      assertTypeError("Gateway.AccessRequest(GatewayAccess.GetRobots(null))")
      assertTypeError("RobotActor.Asked(RobotAccess.GetSnapshot(null))")
      assertTypeError("ResponseActor.Called(null)")
      assertTypeError("VisionActor.Registering(null)")
    }
  }
}
