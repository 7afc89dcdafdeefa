package naogateway.actors

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ManualTime, ScalaTestWithActorTestKit, TestProbe}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway._
import naogateway.actors.RobotStandIn.reachable
import naogateway.wire.{RpcCall, RpcReply, RpcValue}

class NoResponseActorSpec extends ScalaTestWithActorTestKit(ManualTime.config) with AnyWordSpecLike with LogCapturing {
  private val manualTime = ManualTime()
  private val settings = CallSettings(1.second, idempotentRetries = 0, stashCapacity = 3)

  private def sent(robot: TestProbe[RobotActor.FromChild]): RpcCall =
    robot.expectMessageType[RobotActor.Transmit].out match {
      case RobotActor.Outbound.CallOut(call) => call
      case other                           => fail(s"unexpected $other")
    }

  private def say(text: String) = RpcCall("speech", "say", Vector(RpcValue.Text(text)))
  private def walk(v: Float) = RpcCall("motion", "walk", Vector(RpcValue.Number(v), RpcValue.Number(0), RpcValue.Number(0)))

  "NoResponseActor" must {
    "send one command at a time, in order, each after the previous one's answer" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val actor = spawn(NoResponseActor(4, settings, robot.ref, online = true))
      reachable(robot)
      Seq("a", "b", "c").foreach(t => actor ! NoResponseActor.Send(say(t)))
      val a = sent(robot)
      a.params shouldBe Vector(RpcValue.Text("a"))
      (a.callId.get >>> 30) shouldBe 1
      robot.expectNoMessage(Duration.Zero)
      actor ! NoResponseActor.ReplyReceived(RpcReply(Right(Some(RpcValue.Flag(true))), a.callId))
      val b = sent(robot)
      b.params shouldBe Vector(RpcValue.Text("b"))
      // A lost answer does not block the queue for ever.
      manualTime.timePasses(1.second)
      sent(robot).params shouldBe Vector(RpcValue.Text("c"))
    }
    "let a newer walk replace the stashed one (latest wins) and tell the replaced caller" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val replies = createTestProbe[CallResult]()
      val actor = spawn(NoResponseActor(4, settings, robot.ref, online = true))
      reachable(robot)
      actor ! NoResponseActor.Send(say("first"))
      val first = sent(robot)
      actor ! NoResponseActor.Send(walk(0.1f), Some(replies.ref))
      actor ! NoResponseActor.Send(say("between"))
      actor ! NoResponseActor.Send(walk(0.2f), Some(replies.ref))
      actor ! NoResponseActor.Send(walk(0.3f), Some(replies.ref))
      replies.expectMessage(CallResult(4, "motion.walk", Left(CallError.Superseded(4, "motion.walk"))))
      replies.expectMessage(CallResult(4, "motion.walk", Left(CallError.Superseded(4, "motion.walk"))))
      actor ! NoResponseActor.ReplyReceived(RpcReply(Right(None), first.callId))
      val w = sent(robot)
      w.params.head shouldBe RpcValue.Number(0.3f)
      actor ! NoResponseActor.ReplyReceived(RpcReply(Right(Some(RpcValue.Flag(true))), w.callId))
      replies.expectMessage(CallResult(4, "motion.walk", Right(Some(RpcValue.Flag(true)))))
      sent(robot).params shouldBe Vector(RpcValue.Text("between"))
    }
    "answer each waiting command exactly once when stopped, the newest replacement instead of the replaced one" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val replies = createTestProbe[CallResult]()
      val actor = spawn(NoResponseActor(4, settings, robot.ref, online = true))
      reachable(robot)
      actor ! NoResponseActor.Send(say("busy"), Some(replies.ref))
      sent(robot)
      actor ! NoResponseActor.Send(walk(0.1f), Some(replies.ref))
      actor ! NoResponseActor.Send(walk(0.2f), Some(replies.ref))
      replies.expectMessage(CallResult(4, "motion.walk", Left(CallError.Superseded(4, "motion.walk"))))
      testKit.stop(actor)
      val last = replies.receiveMessages(2)
      last.map(_.call).sorted shouldBe Seq("motion.walk", "speech.say")
      last.foreach(_.result shouldBe Left(CallError.RobotOffline(4)))
      replies.expectNoMessage(200.millis)
    }
    "answer an overflow with an error instead of dropping silently" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val replies = createTestProbe[CallResult]()
      val actor = spawn(NoResponseActor(4, settings, robot.ref, online = true))
      reachable(robot)
      (1 to 5).foreach(i => actor ! NoResponseActor.Send(say(s"$i"), Some(replies.ref)))
      sent(robot)
      replies.expectMessageType[CallResult].result.left.toOption.get shouldBe a[CallError.Overloaded]
    }
    "fail everything waiting when the robot goes offline, and fail fast while offline" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val replies = createTestProbe[CallResult]()
      val actor = spawn(NoResponseActor(4, settings, robot.ref, online = true))
      reachable(robot)
      actor ! NoResponseActor.Send(say("1"), Some(replies.ref))
      actor ! NoResponseActor.Send(say("2"), Some(replies.ref))
      sent(robot)
      actor ! NoResponseActor.Reachability(false)
      replies.receiveMessages(2).map(_.result) shouldBe Seq.fill(2)(Left(CallError.RobotOffline(4)))
      actor ! NoResponseActor.Send(say("3"), Some(replies.ref))
      replies.expectMessage(CallResult(4, "speech.say", Left(CallError.RobotOffline(4))))
      robot.expectMessage(RobotActor.Wanted)
    }
  }
}
