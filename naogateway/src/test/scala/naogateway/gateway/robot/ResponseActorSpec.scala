package naogateway.gateway.robot

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ManualTime, ScalaTestWithActorTestKit, TestProbe}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.RobotAccess
import naogateway.api.{CallResult, Priority, RobotFailure}
import naogateway.gateway.CallSettings
import naogateway.gateway.robot.RobotStandIn.{callActors, sent}
import naogateway.wire.{RpcCall, RpcReply, RpcValue}

class ResponseActorSpec extends ScalaTestWithActorTestKit(ManualTime.config) with AnyWordSpecLike with LogCapturing {
  private val manualTime = ManualTime()
  private val settings = CallSettings(2.seconds, idempotentRetries = 2, stashCapacity = 2)

  /** The next attempt the robot's sender handed the outbox; the robot actor only counts it. */
  private def transmitted(outbox: TestProbe[Outbox.Command]): (Long, RpcCall, Outbox.Send) = {
    val (call, send) = sent(outbox)
    send.tag shouldBe call.callId.get
    (call.callId.get, call, send)
  }

  "ResponseActor" must {
    "pair a reply with its call by call id and answer exactly once" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val outbox = createTestProbe[Outbox.Command]()
      val caller = createTestProbe[CallResult]()
      val (responder, _) = callActors(testKit, 3, settings, robot, outbox)
      responder ! RobotAccess.Call(RpcCall("system", "battery", Vector.empty), caller.ref)
      responder ! RobotAccess.Call(RpcCall("system", "ping", Vector.empty), caller.ref)
      val (first, _, _) = transmitted(outbox)
      val (second, _, _) = transmitted(outbox)
      CallId.ownerOf(first) shouldBe Some(CallId.Owner.Response)
      responder ! ResponseActor.ReplyReceived(RpcReply(Right(Some(RpcValue.UInt(99))), Some(second)))
      caller.expectMessage(CallResult(3, "system.ping", Right(Some(RpcValue.UInt(99)))))
      robot.expectMessageType[RobotActor.RoundTrip]
      responder ! ResponseActor.ReplyReceived(RpcReply(Left("flat"), Some(first)))
      caller.expectMessage(CallResult(3, "system.battery", Left(RobotFailure.RobotError(3, "flat"))))
      // A duplicate reply finds no pending call and is not answered twice.
      responder ! ResponseActor.ReplyReceived(RpcReply(Left("flat"), Some(first)))
      caller.expectNoMessage(100.millis)
    }
    "resend an idempotent call as new requests with new call ids, then time out with one answer (protocol.md 7.1)" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val outbox = createTestProbe[Outbox.Command]()
      val caller = createTestProbe[CallResult]()
      val (responder, _) = callActors(testKit, 3, settings, robot, outbox)
      responder ! RobotAccess.Call(RpcCall("motion", "stop", Vector.empty), caller.ref)
      val (first, _, _) = transmitted(outbox)
      manualTime.timePasses(667.millis)
      robot.expectMessage(RobotActor.Retransmitted)
      val (second, c2, _) = transmitted(outbox)
      manualTime.timePasses(667.millis)
      robot.expectMessage(RobotActor.Retransmitted)
      val (third, _, _) = transmitted(outbox)
      // A robot answers every request once: a repeated call id would earn two answers to one request.
      Set(first, second, third) should have size 3
      Seq(second, third).foreach(id => CallId.ownerOf(id) shouldBe Some(CallId.Owner.Response))
      c2 shouldBe RpcCall("motion", "stop", Vector.empty, Some(second))
      manualTime.timePasses(667.millis)
      caller.expectMessage(CallResult(3, "motion.stop",
          Left(RobotFailure.Timeout(3, "motion.stop", (2.seconds).toMillis))))
      outbox.expectNoMessage(Duration.Zero)
    }
    "complete a resent call with the late answer to an earlier attempt, once" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val outbox = createTestProbe[Outbox.Command]()
      val caller = createTestProbe[CallResult]()
      val (responder, _) = callActors(testKit, 3, settings, robot, outbox)
      responder ! RobotAccess.Call(RpcCall("motion", "getPosture", Vector.empty), caller.ref)
      val (first, _, _) = transmitted(outbox)
      manualTime.timePasses(667.millis)
      robot.expectMessage(RobotActor.Retransmitted)
      val (second, _, _) = transmitted(outbox)
      responder ! ResponseActor.ReplyReceived(RpcReply(Right(Some(RpcValue.Text("sit"))), Some(first)))
      caller.expectMessage(CallResult(3, "motion.getPosture", Right(Some(RpcValue.Text("sit")))))
      // The second attempt's answer finds the call settled; no sample from a call sent twice (Karn's rule).
      responder ! ResponseActor.ReplyReceived(RpcReply(Right(Some(RpcValue.Text("sit"))), Some(second)))
      caller.expectNoMessage(100.millis)
      manualTime.timePasses(2.seconds)
      outbox.expectNoMessage(Duration.Zero)
    }
    "send a call that is not idempotent only once" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val outbox = createTestProbe[Outbox.Command]()
      val caller = createTestProbe[CallResult]()
      val (responder, _) = callActors(testKit, 3, settings, robot, outbox)
      responder ! RobotAccess.Call(RpcCall("speech", "say", Vector(RpcValue.Text("hi"))), caller.ref)
      transmitted(outbox)
      manualTime.timePasses(2.seconds)
      caller.expectMessageType[CallResult].result.left.toOption.get shouldBe a[RobotFailure.Timeout]
      outbox.expectNoMessage(Duration.Zero)
    }
    "fail pending and new calls fast when the robot goes offline" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val outbox = createTestProbe[Outbox.Command]()
      val caller = createTestProbe[CallResult]()
      val (responder, _) = callActors(testKit, 3, settings, robot, outbox)
      responder ! RobotAccess.Call(RpcCall("system", "ping", Vector.empty), caller.ref)
      transmitted(outbox)
      responder ! ResponseActor.Reachability(false)
      caller.expectMessage(CallResult(3, "system.ping", Left(RobotFailure.RobotOffline(3))))
      responder ! RobotAccess.Call(RpcCall("system", "ping", Vector.empty), caller.ref)
      caller.expectMessage(CallResult(3, "system.ping", Left(RobotFailure.RobotOffline(3))))
      robot.expectMessage(RobotActor.Wanted)
    }
    "keep at most four calls in flight, stash a bounded number and refuse the rest with an error" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val outbox = createTestProbe[Outbox.Command]()
      val caller = createTestProbe[CallResult]()
      val (responder, _) = callActors(testKit, 3, settings, robot, outbox)
      (1 to 7).foreach(i =>
        responder ! RobotAccess.Call(RpcCall("speech", "say", Vector(RpcValue.Text(s"$i"))), caller.ref))
      val ids = (1 to 4).map(_ => transmitted(outbox)._1)
      caller.expectMessageType[CallResult].result shouldBe Left(RobotFailure.Overloaded(3,
          "4 calls in flight and 2 waiting"))
      outbox.expectNoMessage(Duration.Zero)
      responder ! ResponseActor.ReplyReceived(RpcReply(Right(None), Some(ids.head)))
      caller.expectMessageType[CallResult].result shouldBe Right(None)
      robot.expectMessageType[RobotActor.RoundTrip]
      transmitted(outbox)._2 shouldBe RpcCall("speech", "say", Vector(RpcValue.Text("5")), Some(ids.last + 1))
    }
    "start a waiting call's deadline only when it leaves, so its attempts are not spent waiting for room" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val outbox = createTestProbe[Outbox.Command]()
      val caller = createTestProbe[CallResult]()
      val (responder, _) = callActors(testKit, 3, settings, robot, outbox)
      (1 to 4).foreach(i =>
        responder ! RobotAccess.Call(RpcCall("speech", "say", Vector(RpcValue.Text(s"$i"))), caller.ref))
      val busy = (1 to 4).map(_ => transmitted(outbox)._1)
      responder ! RobotAccess.Call(RpcCall("system", "ping", Vector.empty), caller.ref)
      outbox.expectNoMessage(100.millis)
      // Longer than one attempt of the ping: it has not left, so it is neither resent nor timed out.
      manualTime.timePasses(1.second)
      robot.expectNoMessage(Duration.Zero)
      responder ! ResponseActor.ReplyReceived(RpcReply(Right(None), Some(busy.head)))
      caller.expectMessageType[CallResult].call shouldBe "speech.say"
      robot.expectMessageType[RobotActor.RoundTrip]
      val (ping, _, _) = transmitted(outbox)
      // Now its three attempts of 667 ms each run: the first resend comes one attempt after it left.
      manualTime.timePasses(600.millis)
      outbox.expectNoMessage(Duration.Zero)
      manualTime.timePasses(100.millis)
      robot.expectMessage(RobotActor.Retransmitted)
      transmitted(outbox)._2.name shouldBe "system.ping"
      responder ! ResponseActor.ReplyReceived(RpcReply(Right(Some(RpcValue.UInt(1))), Some(ping)))
      caller.expectMessage(CallResult(3, "system.ping", Right(Some(RpcValue.UInt(1)))))
    }
    "fail a call at once with the rule when the outbox refuses it" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val outbox = createTestProbe[Outbox.Command]()
      val caller = createTestProbe[CallResult]()
      val (responder, _) = callActors(testKit, 3, settings, robot, outbox)
      responder ! RobotAccess.Call(RpcCall("system", "ping", Vector.empty), caller.ref)
      val (id, _, t) = transmitted(outbox)
      t.replyTo.get ! Outbox.RefusedByRule(id, Outbox.NoSendingWhileGameRuns)
      caller.expectMessage(CallResult(3, "system.ping", Left(RobotFailure.RuleGate(Outbox.NoSendingWhileGameRuns))))
    }
    "supersede an older call of a slot: no more retries, its caller told, its held datagrams withdrawn before the next goes" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val outbox = createTestProbe[Outbox.Command]()
      val caller = createTestProbe[CallResult]()
      val (responder, _) = callActors(testKit, 3, settings, robot, outbox)
      responder ! RobotAccess.Call(RpcCall("motion", "walk", Vector.fill(3)(RpcValue.Number(0.2f))), caller.ref)
      val (walk, _, _) = transmitted(outbox)
      responder ! RobotAccess.Call(RpcCall("motion", "stop", Vector.empty), caller.ref, Priority.Safety)
      caller.expectMessage(CallResult(3, "motion.walk", Left(RobotFailure.Superseded(3, "motion.walk"))))
      // The withdrawal reaches the outbox before the stop: a walk held behind the budget cannot follow the stop.
      outbox.expectMessage(Outbox.Withdraw(3, Set(walk)))
      val (stop, call, send) = transmitted(outbox)
      call.name shouldBe "motion.stop"
      send.priority shouldBe Priority.Safety
      manualTime.timePasses(667.millis)
      robot.expectMessage(RobotActor.Retransmitted)
      val (_, again, _) = transmitted(outbox)
      again.name shouldBe "motion.stop"
      // Only the stop is retried, never the superseded walk; a late answer to the walk changes nothing.
      responder ! ResponseActor.ReplyReceived(RpcReply(Right(None), Some(walk)))
      responder ! ResponseActor.ReplyReceived(RpcReply(Right(Some(RpcValue.Flag(true))), Some(stop)))
      caller.expectMessage(CallResult(3, "motion.stop", Right(Some(RpcValue.Flag(true)))))
      manualTime.timePasses(2.seconds)
      outbox.expectNoMessage(Duration.Zero)
    }
    "send a safety call at once even with four calls in flight, and let the newest head target win the wait" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val outbox = createTestProbe[Outbox.Command]()
      val caller = createTestProbe[CallResult]()
      val (responder, _) = callActors(testKit, 3, settings, robot, outbox)
      (1 to 4).foreach(i =>
        responder ! RobotAccess.Call(RpcCall("speech", "say", Vector(RpcValue.Text(s"$i"))), caller.ref))
      val busy = (1 to 4).map(_ => transmitted(outbox)._1)
      def head(pan: Float) = RpcCall("motion", "head", Vector(RpcValue.Number(pan), RpcValue.Number(0f)))
      responder ! RobotAccess.Call(head(0.1f), caller.ref)
      responder ! RobotAccess.Call(head(0.2f), caller.ref)
      caller.expectMessage(CallResult(3, "motion.head", Left(RobotFailure.Superseded(3, "motion.head"))))
      responder ! RobotAccess.Call(RpcCall("motion", "stop", Vector.empty), caller.ref, Priority.Safety)
      val (stop, stopCall, _) = transmitted(outbox)
      stopCall.name shouldBe "motion.stop"
      responder ! ResponseActor.ReplyReceived(RpcReply(Right(None), Some(stop)))
      caller.expectMessageType[CallResult].call shouldBe "motion.stop"
      robot.expectMessageType[RobotActor.RoundTrip]
      // The four ordinary calls still fill the room: the head waits.
      outbox.expectNoMessage(Duration.Zero)
      responder ! ResponseActor.ReplyReceived(RpcReply(Right(None), Some(busy.head)))
      caller.expectMessageType[CallResult].call shouldBe "speech.say"
      robot.expectMessageType[RobotActor.RoundTrip]
      transmitted(outbox)._2.params shouldBe Vector(RpcValue.Number(0.2f), RpcValue.Number(0f))
    }
  }
}
