package robotmiddleware

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.time.{Seconds, Span}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.RobotFailure
import naogateway.wire.ActuatorGroup

/** The facade fails every future with a `RobotFailure` (docs/writing-apps.md, Failures), and never throws. */
class RobotInterfaceSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  private def connected(): (RobotInterface, akka.actor.testkit.typed.scaladsl.TestProbe[RobotMiddleware.Command]) = {
    val middleware = createTestProbe[RobotMiddleware.Command]()
    val interface = RobotClient.connect(system, middleware.ref, "silent-test", timeout = 100.millis)
    middleware.expectMessageType[RobotMiddleware.RegisterApp].replyTo ! RobotMiddleware.AppRegistered("silent-test")
    (interface.futureValue, middleware)
  }

  "RobotInterface" should {
    "fail an operation the middleware never answers with RobotFailure.Timeout, not an ask timeout" in {
      val (interface, middleware) = connected()
      val stopped = interface.stop(4)
      middleware.expectMessageType[RobotMiddleware.Execute].robotId shouldBe 4
      // The ask waits the interface's timeout plus the 5 s margin for posture changes.
      val failure = stopped.failed.futureValue(timeout(Span(8, Seconds)))
      failure shouldBe a[RobotFailure.Timeout]
      failure.asInstanceOf[RobotFailure.Timeout].robotId shouldBe 4
    }

    "ask for a set of leases in one request, so the middleware grants all of them or none" in {
      val (interface, middleware) = connected()
      val acquired = interface.acquire(4, ActuatorGroup.Walk, ActuatorGroup.Head, ActuatorGroup.Walk)
      val request = middleware.expectMessageType[RobotMiddleware.Acquire]
      request.groups shouldBe Set[ActuatorGroup](ActuatorGroup.Walk, ActuatorGroup.Head)
      middleware.expectNoMessage(100.millis)
      request.replyTo ! RobotMiddleware.LeaseResult(4, request.groups, Left(RobotFailure.LeaseNotHeld(4, ActuatorGroup.Head, Some("referee"))))
      acquired.failed.futureValue shouldBe RobotFailure.LeaseNotHeld(4, ActuatorGroup.Head, Some("referee"))
    }

    "fail a walk with velocities that are no numbers in the future, without sending it" in {
      val (interface, middleware) = connected()
      val walked = interface.walk(4, Double.NaN, 0.0, Double.PositiveInfinity)
      walked.failed.futureValue shouldBe RobotFailure.RobotError(4, "out of range: walk velocities must be finite numbers")
      middleware.expectNoMessage(100.millis)
    }
  }
}
