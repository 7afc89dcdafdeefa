package naogateway.gateway.robot

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, LoggingTestKit, ScalaTestWithActorTestKit}
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{Behavior, BehaviorInterceptor, SupervisorStrategy, TypedActorContext}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.RobotAccess
import naogateway.api.{CallResult, RobotFailure}
import naogateway.gateway.CallSettings
import naogateway.gateway.robot.RobotStandIn.callActors
import naogateway.wire.{RpcCall, RpcValue}

/** A child that really crashes, under the supervision the robot actor gives it, still answers its callers. */
class ChildRestartSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  private val settings = CallSettings(5.seconds, idempotentRetries = 0, stashCapacity = 4)

  /** Once armed, throws on the first message `crash` picks: a stand-in for any bug. */
  private final class CrashOn[T: scala.reflect.ClassTag](crash: T => Boolean) extends BehaviorInterceptor[T, T] {
    @volatile private var armed = false
    def arm(): Unit = armed = true
    def aroundReceive(ctx: TypedActorContext[T], msg: T, target: BehaviorInterceptor.ReceiveTarget[T]): Behavior[T] =
      if (armed && crash(msg)) {
        armed = false
        throw new IllegalStateException("injected failure")
      } else target(ctx, msg)
  }

  private val restart = SupervisorStrategy.restartWithBackoff(50.millis, 200.millis, 0.0)

  "A crashing response actor" must {
    "answer its pending and waiting calls with Interrupted, and serve new calls after the restart" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val outbox = createTestProbe[Outbox.Command]()
      val caller = createTestProbe[CallResult]()
      val crash = new CrashOn[Any]({ case ResponseActor.Reachability(true) => true; case _ => false })
      val (responder, _) = callActors(testKit, 2, settings, robot, outbox,
        wrapResponder = b => Behaviors.supervise(Behaviors.intercept(() => crash)(b)).onFailure(restart))
      (1 to 5).foreach(i =>
        responder ! RobotAccess.Call(RpcCall("speech", "say", Vector(RpcValue.Text(s"$i"))), caller.ref))
      outbox.receiveMessages(4) // four in flight, one waiting
      crash.arm()
      LoggingTestKit.error[IllegalStateException].withMessageContains("injected failure").expect {
        responder ! ResponseActor.Reachability(true)
      }
      val answers = caller.receiveMessages(5)
      answers.foreach(_.result.left.toOption.get shouldBe a[RobotFailure.Interrupted])
      // After the back-off the restarted actor asks again whether the robot is reachable.
      robot.fishForMessage(3.seconds) {
        case _: RobotActor.ReachabilityWanted => akka.actor.testkit.typed.FishingOutcome.Complete
        case _                                => akka.actor.testkit.typed.FishingOutcome.ContinueAndIgnore
      }.last.asInstanceOf[RobotActor.ReachabilityWanted].replyTo ! true
      // The interrupted calls gave their room back to the sender: a new call goes out at once.
      responder ! RobotAccess.Call(RpcCall("system", "ping", Vector.empty), caller.ref)
      outbox.fishForMessage(3.seconds) {
        case s: Outbox.Send if RobotStandIn.callIn(s).name == "system.ping" =>
          akka.actor.testkit.typed.FishingOutcome.Complete
        case _ => akka.actor.testkit.typed.FishingOutcome.ContinueAndIgnore
      }
    }

    "still know after a restart that the robot is offline, and fail calls at once" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val outbox = createTestProbe[Outbox.Command]()
      val caller = createTestProbe[CallResult]()
      val crash =
        new CrashOn[Any]({ case ResponseActor.Reachability(false) => true; case _ => false })
      val (responder, _) = callActors(testKit, 2, settings, robot, outbox,
        wrapResponder = b => Behaviors.supervise(Behaviors.intercept(() => crash)(b)).onFailure(restart))
      crash.arm()
      LoggingTestKit.error[IllegalStateException].withMessageContains("injected failure").expect {
        responder ! ResponseActor.Reachability(false)
      }
      // The restarted actor starts from its spawn-time assumption (online) until the robot actor answers.
      RobotStandIn.reachable(robot, online = false)
      responder ! RobotAccess.Call(RpcCall("system", "ping", Vector.empty), caller.ref)
      caller.expectMessageType[CallResult].result shouldBe Left(RobotFailure.RobotOffline(2))
      robot.expectMessage(RobotActor.Wanted)
    }
  }

  "A crashing no-response actor" must {
    "answer the commands in its order with Interrupted, then take commands again" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val outbox = createTestProbe[Outbox.Command]()
      val caller = createTestProbe[CallResult]()
      val crash = new CrashOn[NoResponseActor.Command]({
        case NoResponseActor.Submit(RobotFrames.Outbound.CallOut(call), _, _, _, _, _) =>
          call.params == Vector(RpcValue.Text("boom"))
        case _ => false
      })
      val (responder, _) = callActors(testKit, 2, settings, robot, outbox,
        wrapSender = b => Behaviors.supervise(Behaviors.intercept(() => crash)(b)).onFailure(restart))
      (1 to 3).foreach(i =>
        RobotTestHooks.sendOnce(responder, RpcCall("speech", "say", Vector(RpcValue.Text(s"$i"))), Some(caller.ref)))
      outbox.receiveMessages(3)
      crash.arm()
      LoggingTestKit.error[IllegalStateException].withMessageContains("injected failure").expect {
        RobotTestHooks.sendOnce(responder, RpcCall("speech", "say", Vector(RpcValue.Text("boom"))))
      }
      caller.receiveMessages(3).foreach(_.result.left.toOption.get shouldBe a[RobotFailure.Interrupted])
      caller.expectNoMessage(200.millis)
      // The new incarnation asks for its route again before it sends anything.
      robot.fishForMessage(3.seconds) {
        case _: RobotActor.RouteWanted => akka.actor.testkit.typed.FishingOutcome.Complete
        case _                         => akka.actor.testkit.typed.FishingOutcome.ContinueAndIgnore
      }.last.asInstanceOf[RobotActor.RouteWanted].replyTo ! NoResponseActor.RouteChanged(RobotStandIn.route(outbox.ref))
      RobotTestHooks.sendOnce(responder, RpcCall("speech", "say", Vector(RpcValue.Text("again"))))
      RobotStandIn.sent(outbox)._1.params shouldBe Vector(RpcValue.Text("again"))
    }
  }
}
