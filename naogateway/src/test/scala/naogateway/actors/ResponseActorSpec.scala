package naogateway.actors

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ManualTime, ScalaTestWithActorTestKit, TestProbe}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway._
import naogateway.actors.RobotStandIn.reachable
import naogateway.wire.{RpcCall, RpcReply, RpcValue}

class ResponseActorSpec extends ScalaTestWithActorTestKit(ManualTime.config) with AnyWordSpecLike with LogCapturing {
  private val manualTime = ManualTime()
  private val settings = CallSettings(2.seconds, idempotentRetries = 2, stashCapacity = 2)

  private def transmitted(robot: TestProbe[RobotActor.FromChild]): (Long, RobotActor.Transmit) =
    robot.expectMessageType[RobotActor.Transmit] match {
      case t @ RobotActor.Transmit(RobotActor.Outbound.CallOut(call), _, _, _) => (call.callId.get, t)
      case other                                                           => fail(s"unexpected $other")
    }

  "ResponseActor" must {
    "pair a reply with its call by call id and answer exactly once" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val caller = createTestProbe[CallResult]()
      val responder = spawn(ResponseActor(3, settings, robot.ref, online = true))
      reachable(robot)
      responder ! ResponseActor.Call(RpcCall("system", "battery", Vector.empty), caller.ref)
      responder ! ResponseActor.Call(RpcCall("system", "ping", Vector.empty), caller.ref)
      val (first, _) = transmitted(robot)
      val (second, _) = transmitted(robot)
      (first >>> 30) shouldBe 0
      responder ! ResponseActor.ReplyReceived(RpcReply(Right(Some(RpcValue.UInt(99))), Some(second)))
      caller.expectMessage(CallResult(3, "system.ping", Right(Some(RpcValue.UInt(99)))))
      robot.expectMessageType[RobotActor.RoundTrip]
      responder ! ResponseActor.ReplyReceived(RpcReply(Left("flat"), Some(first)))
      caller.expectMessage(CallResult(3, "system.battery", Left(CallError.RobotError(3, "flat"))))
      // A duplicate reply finds no pending call and is not answered twice.
      responder ! ResponseActor.ReplyReceived(RpcReply(Left("flat"), Some(first)))
      caller.expectNoMessage(100.millis)
    }
    "resend an idempotent call as new requests with new call ids, then time out with one answer (protocol.md 7.1)" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val caller = createTestProbe[CallResult]()
      val responder = spawn(ResponseActor(3, settings, robot.ref, online = true))
      reachable(robot)
      responder ! ResponseActor.Call(RpcCall("motion", "stop", Vector.empty), caller.ref)
      val (first, _) = transmitted(robot)
      manualTime.timePasses(667.millis)
      robot.expectMessage(RobotActor.Retransmitted)
      val (second, t2) = transmitted(robot)
      manualTime.timePasses(667.millis)
      robot.expectMessage(RobotActor.Retransmitted)
      val (third, _) = transmitted(robot)
      // A robot answers every request once: a repeated call id would earn two answers to one request.
      Set(first, second, third) should have size 3
      Seq(second, third).foreach(id => (id >>> 30) shouldBe 0)
      t2.out shouldBe RobotActor.Outbound.CallOut(RpcCall("motion", "stop", Vector.empty, Some(second)))
      manualTime.timePasses(667.millis)
      caller.expectMessage(CallResult(3, "motion.stop", Left(CallError.Timeout(3, "motion.stop", 2.seconds))))
      robot.expectNoMessage(Duration.Zero)
    }
    "complete a resent call with the late answer to an earlier attempt, once" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val caller = createTestProbe[CallResult]()
      val responder = spawn(ResponseActor(3, settings, robot.ref, online = true))
      reachable(robot)
      responder ! ResponseActor.Call(RpcCall("motion", "getPosture", Vector.empty), caller.ref)
      val (first, _) = transmitted(robot)
      manualTime.timePasses(667.millis)
      robot.expectMessage(RobotActor.Retransmitted)
      val (second, _) = transmitted(robot)
      responder ! ResponseActor.ReplyReceived(RpcReply(Right(Some(RpcValue.Text("sit"))), Some(first)))
      caller.expectMessage(CallResult(3, "motion.getPosture", Right(Some(RpcValue.Text("sit")))))
      // The second attempt's answer finds the call settled; no sample from a call sent twice (Karn's rule).
      responder ! ResponseActor.ReplyReceived(RpcReply(Right(Some(RpcValue.Text("sit"))), Some(second)))
      caller.expectNoMessage(100.millis)
      manualTime.timePasses(2.seconds)
      robot.expectNoMessage(Duration.Zero)
    }
    "send a call that is not idempotent only once" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val caller = createTestProbe[CallResult]()
      val responder = spawn(ResponseActor(3, settings, robot.ref, online = true))
      reachable(robot)
      responder ! ResponseActor.Call(RpcCall("speech", "say", Vector(RpcValue.Text("hi"))), caller.ref)
      transmitted(robot)
      manualTime.timePasses(2.seconds)
      caller.expectMessageType[CallResult].result.left.toOption.get shouldBe a[CallError.Timeout]
      robot.expectNoMessage(Duration.Zero)
    }
    "fail pending and new calls fast when the robot goes offline" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val caller = createTestProbe[CallResult]()
      val responder = spawn(ResponseActor(3, settings, robot.ref, online = true))
      reachable(robot)
      responder ! ResponseActor.Call(RpcCall("system", "ping", Vector.empty), caller.ref)
      transmitted(robot)
      responder ! ResponseActor.Reachability(false)
      caller.expectMessage(CallResult(3, "system.ping", Left(CallError.RobotOffline(3))))
      responder ! ResponseActor.Call(RpcCall("system", "ping", Vector.empty), caller.ref)
      caller.expectMessage(CallResult(3, "system.ping", Left(CallError.RobotOffline(3))))
      robot.expectMessage(RobotActor.Wanted)
    }
    "keep at most four calls in flight, stash a bounded number and refuse the rest with an error" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val caller = createTestProbe[CallResult]()
      val responder = spawn(ResponseActor(3, settings, robot.ref, online = true))
      reachable(robot)
      (1 to 7).foreach(i => responder ! ResponseActor.Call(RpcCall("speech", "say", Vector(RpcValue.Text(s"$i"))), caller.ref))
      val ids = (1 to 4).map(_ => transmitted(robot)._1)
      caller.expectMessageType[CallResult].result shouldBe Left(CallError.Overloaded(3, "4 calls in flight and 2 waiting"))
      robot.expectNoMessage(Duration.Zero)
      responder ! ResponseActor.ReplyReceived(RpcReply(Right(None), Some(ids.head)))
      caller.expectMessageType[CallResult].result shouldBe Right(None)
      robot.expectMessageType[RobotActor.RoundTrip]
      transmitted(robot)._2.out shouldBe RobotActor.Outbound.CallOut(RpcCall("speech", "say", Vector(RpcValue.Text("5")), Some(ids.last + 1)))
    }
    "fail a call at once with the rule when the outbox refuses it" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val caller = createTestProbe[CallResult]()
      val responder = spawn(ResponseActor(3, settings, robot.ref, online = true))
      reachable(robot)
      responder ! ResponseActor.Call(RpcCall("system", "ping", Vector.empty), caller.ref)
      val (id, t) = transmitted(robot)
      t.outcome.get ! Outbox.RefusedByRule(id, Outbox.NoSendingWhileGameRuns)
      caller.expectMessage(CallResult(3, "system.ping", Left(CallError.RuleGate(Outbox.NoSendingWhileGameRuns))))
    }
  }
}
