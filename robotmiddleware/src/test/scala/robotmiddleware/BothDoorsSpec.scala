package robotmiddleware

import scala.concurrent.Await
import scala.concurrent.duration._

import akka.Done
import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.actor.typed.ActorRef
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.api.{RobotFailure, RobotOnline}
import naogateway.integration.GatewayFixture
import naogateway.sim.{ReceivedCall, SimulatedRobot}
import naogateway.wire.{ActuatorGroup, RpcValue}

/** The two doors of `RobotInterface` in the gateway's own actor system, seen at a simulated robot's receive log: a send
  * keeps its place among the app's calls, its answer is dropped, and it is refused as a call is. Loopback only.
  */
class BothDoorsSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {
  private val settings = MiddlewareSettings(10.8, 11.0, 200.millis, 2.seconds, 5.seconds, 1.second, 64)
  private val Patience = 30.seconds

  private def received(robot: ActorRef[SimulatedRobot.Command]): Vector[ReceivedCall] = {
    val probe = createTestProbe[Vector[ReceivedCall]]()
    robot ! SimulatedRobot.GetReceivedCalls(probe.ref)
    probe.receiveMessage(10.seconds)
  }

  private def said(robot: ActorRef[SimulatedRobot.Command]): Vector[String] =
    received(robot).map(_.call).filter(_.name == "speech.say").flatMap(_.params.collect { case RpcValue.Text(t) => t })

  /** The doors' order, not the robot's liveness, is under test: a JVM stalled on a loaded machine (two modules' test
    * JVMs run at once) must not take the robot offline mid-test, so it is given 2 s of silence before the probes.
    */
  private def fixture() = new GatewayFixture(testKit, "heartbeat { quiet-after = 2s, probe-timeout = 500ms }")

  "RobotInterface's two doors" must {
    "keep a send's place among the app's calls, drop its answer, and refuse it without the lease" in {
      val f = fixture()
      try {
        val (robot, _) = f.robot(31)
        f.awaitEvent(Patience) { case RobotOnline(31, _) => () }
        val middleware = spawn(RobotMiddleware(f.gateway, settings))
        val app = Await.result(RobotClient.connect(system, middleware, "two-doors", 1), Patience)

        // Refused: no speech lease yet. It fails as a call would, and nothing reaches the robot.
        app.send(31, "speech", "say", RpcValue.Text("refused")).failed.futureValue(timeout(Patience)) shouldBe
          RobotFailure.LeaseNotHeld(31, ActuatorGroup.Speech, None)
        Await.result(app.acquire(31, ActuatorGroup.Speech), Patience) shouldBe Done

        // Sends and calls interleaved without waiting: the robot hears them in the order the app made them.
        val made = (1 to 6).map { i =>
          if (i % 2 == 1) app.send(31, "speech", "say", RpcValue.Text(s"send-$i"))
          else app.call(31, "speech", "say", RpcValue.Text(s"call-$i"))
        }
        made.foreach(m => Await.result(m, Patience))
        eventually(timeout(Patience)) { said(robot).size shouldBe 6 }
        said(robot) shouldBe (1 to 6).map(i => if (i % 2 == 1) s"send-$i" else s"call-$i")
        said(robot) should not contain "refused"

        // The robot answers this one with an error; the send was accepted, so the error is dropped, not reported.
        Await.result(app.send(31, "nosuch", "method"), Patience) shouldBe Done
        eventually(timeout(Patience)) { received(robot).map(_.call.name) should contain("nosuch.method") }
        // A call of the same kind does get the robot's error: only the send door drops it.
        app.call(31, "nosuch", "method").failed.futureValue(timeout(Patience)) shouldBe a[RobotFailure.RobotError]
        app.close()
      } finally f.stop()
    }

    "take a typed operation through the send door, with the guard's checks (a walk needs its lease)" in {
      val f = fixture()
      try {
        val (robot, _) = f.robot(32)
        f.awaitEvent(Patience) { case RobotOnline(32, _) => () }
        val middleware = spawn(RobotMiddleware(f.gateway, settings))
        val app = Await.result(RobotClient.connect(system, middleware, "typed-sender", 1), Patience)
        app.send(32, Operation.Head(0.3, 0)).failed.futureValue(timeout(Patience)) shouldBe
          RobotFailure.LeaseNotHeld(32, ActuatorGroup.Head, None)
        Await.result(app.acquire(32, ActuatorGroup.Head), Patience) shouldBe Done
        Await.result(app.send(32, Operation.Head(0.3, 0)), Patience) shouldBe Done
        eventually(timeout(Patience)) { f.view(robot).head._1 shouldBe (0.3 +- 1e-6) }
        app.close()
      } finally f.stop()
    }
  }
}
