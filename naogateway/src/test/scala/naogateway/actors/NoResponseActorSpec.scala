package naogateway.actors

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit, TestProbe}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway._
import naogateway.wire.{RpcCall, RpcValue}

class NoResponseActorSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {
  private val settings = CallSettings(1.second, idempotentRetries = 0, stashCapacity = 3)

  /** The next call the actor hands its sibling response actor: once, without retries. */
  private def called(response: TestProbe[ResponseActor.Command]): ResponseActor.Call = {
    val c = response.expectMessageType[ResponseActor.Call]
    c.idempotent shouldBe Some(false)
    c
  }

  private def say(text: String) = RpcCall("speech", "say", Vector(RpcValue.Text(text)))
  private def walk(v: Float) = RpcCall("motion", "walk", Vector(RpcValue.Number(v), RpcValue.Number(0), RpcValue.Number(0)))
  private def head(pan: Float) = RpcCall("motion", "head", Vector(RpcValue.Number(pan), RpcValue.Number(0)))
  private val stop = RpcCall("motion", "stop", Vector.empty)

  "NoResponseActor" must {
    "hand one command at a time to the response actor, in order, each after the previous one's answer" in {
      val response = createTestProbe[ResponseActor.Command]()
      val replies = createTestProbe[CallResult]()
      val actor = spawn(NoResponseActor(4, settings, response.ref))
      Seq("a", "b", "c").foreach(t => actor ! NoResponseActor.Send(say(t), Some(replies.ref)))
      val a = called(response)
      a.call.params shouldBe Vector(RpcValue.Text("a"))
      response.expectNoMessage(100.millis)
      a.replyTo ! CallResult(4, "speech.say", Right(Some(RpcValue.Flag(true))))
      replies.expectMessage(CallResult(4, "speech.say", Right(Some(RpcValue.Flag(true)))))
      val b = called(response)
      b.call.params shouldBe Vector(RpcValue.Text("b"))
      // A lost answer ends as the response actor's timeout, which lets the next one go.
      b.replyTo ! CallResult(4, "speech.say", Left(RobotFailure.Timeout(4, "speech.say", (1.second).toMillis)))
      called(response).call.params shouldBe Vector(RpcValue.Text("c"))
    }
    "let a newer command of a slot replace the stashed one (latest wins, a stop replaces a walk) and tell the replaced caller" in {
      val response = createTestProbe[ResponseActor.Command]()
      val replies = createTestProbe[CallResult]()
      val actor = spawn(NoResponseActor(4, settings, response.ref))
      actor ! NoResponseActor.Send(say("first"))
      val first = called(response)
      actor ! NoResponseActor.Send(walk(0.1f), Some(replies.ref))
      actor ! NoResponseActor.Send(head(0.1f), Some(replies.ref))
      actor ! NoResponseActor.Send(walk(0.2f), Some(replies.ref))
      actor ! NoResponseActor.Send(head(0.3f), Some(replies.ref))
      actor ! NoResponseActor.Send(stop, Some(replies.ref), Priority.Safety)
      replies.receiveMessages(3).map(_.result) shouldBe Seq(
        Left(RobotFailure.Superseded(4, "motion.walk")), Left(RobotFailure.Superseded(4, "motion.head")),
        Left(RobotFailure.Superseded(4, "motion.walk")))
      first.replyTo ! CallResult(4, "speech.say", Right(None))
      val s = called(response)
      s.call shouldBe stop
      s.priority shouldBe Priority.Safety
      s.replyTo ! CallResult(4, "motion.stop", Right(Some(RpcValue.Flag(true))))
      replies.expectMessage(CallResult(4, "motion.stop", Right(Some(RpcValue.Flag(true)))))
      called(response).call shouldBe head(0.3f)
    }
    "answer each waiting command exactly once when stopped, the newest replacement instead of the replaced one" in {
      val response = createTestProbe[ResponseActor.Command]()
      val replies = createTestProbe[CallResult]()
      val actor = spawn(NoResponseActor(4, settings, response.ref))
      actor ! NoResponseActor.Send(say("busy"), Some(replies.ref))
      called(response)
      actor ! NoResponseActor.Send(walk(0.1f), Some(replies.ref))
      actor ! NoResponseActor.Send(walk(0.2f), Some(replies.ref))
      replies.expectMessage(CallResult(4, "motion.walk", Left(RobotFailure.Superseded(4, "motion.walk"))))
      testKit.stop(actor)
      val last = replies.receiveMessages(2)
      last.map(_.call).sorted shouldBe Seq("motion.walk", "speech.say")
      last.foreach(_.result shouldBe Left(RobotFailure.RobotOffline(4)))
      replies.expectNoMessage(200.millis)
    }
    "answer an overflow with an error instead of dropping silently" in {
      val response = createTestProbe[ResponseActor.Command]()
      val replies = createTestProbe[CallResult]()
      val actor = spawn(NoResponseActor(4, settings, response.ref))
      (1 to 5).foreach(i => actor ! NoResponseActor.Send(say(s"$i"), Some(replies.ref)))
      called(response)
      replies.expectMessageType[CallResult].result.left.toOption.get shouldBe a[RobotFailure.Overloaded]
    }
  }
}
