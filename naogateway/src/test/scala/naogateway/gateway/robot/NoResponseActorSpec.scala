package naogateway.gateway.robot

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ManualTime, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.api.{CallResult, Priority, RobotFailure}
import naogateway.gateway.{BudgetSettings, CallSettings}
import naogateway.gateway.robot.RobotFrames.Outbound
import naogateway.gateway.robot.RobotStandIn.{callActors, sent}
import naogateway.gateway.link.ZeroMqRobotLink
import naogateway.transport.DatagramWriter
import naogateway.proto.{DebuggingCommands, DebuggingOptionNames}
import naogateway.wire.{MessageContents, RpcCall, RpcReply, RpcValue}
import naogateway.wire.gamecontroller.GameState

/** The robot's one sender: everything for the robot in one order, under one in-flight cap, through the outbox. */
class NoResponseActorSpec extends ScalaTestWithActorTestKit(ManualTime.config) with AnyWordSpecLike with LogCapturing {
  private val manualTime = ManualTime()
  private val settings = CallSettings(1.second, idempotentRetries = 2, stashCapacity = 3)

  private def say(text: String) = RpcCall("speech", "say", Vector(RpcValue.Text(text)))
  private def walk(v: Float) =
    RpcCall("motion", "walk", Vector(RpcValue.Number(v), RpcValue.Number(0), RpcValue.Number(0)))
  private def head(pan: Float) = RpcCall("motion", "head", Vector(RpcValue.Number(pan), RpcValue.Number(0)))
  private val stop = RpcCall("motion", "stop", Vector.empty)
  private def probe(id: Long) = RpcCall(HeartBeatActor.ProbeModule, HeartBeatActor.ProbeMethod, Vector.empty, Some(id))

  private def fixture() = {
    val robot = createTestProbe[RobotActor.FromChild]()
    val outbox = createTestProbe[Outbox.Command]()
    val (responder, sender) = callActors(testKit, 4, settings, robot, outbox)
    (robot, outbox, responder, sender)
  }

  /** The robot's reply to the call in `send`. */
  private def reply(
      responder: akka.actor.typed.ActorRef[ResponseActor.Command], send: Outbox.Send, value: RpcValue): Unit =
    responder ! ResponseActor.ReplyReceived(RpcReply(Right(Some(value)), RobotStandIn.callIn(send).callId))

  "NoResponseActor" must {
    "send in order, its reply dropped unless replyTo is given, and never again after a timeout" in {
      val (_, outbox, responder, _) = fixture()
      val replies = createTestProbe[CallResult]()
      RobotTestHooks.sendOnce(responder, say("a"))
      RobotTestHooks.sendOnce(responder, say("b"), Some(replies.ref))
      RobotTestHooks.sendOnce(responder, RpcCall("system", "ping", Vector.empty), Some(replies.ref))
      val (callA, aSend) = sent(outbox)
      val (callB, bSend) = sent(outbox)
      sent(outbox)._1.name shouldBe "system.ping"
      Seq(callA, callB).map(_.params) shouldBe Seq(Vector(RpcValue.Text("a")), Vector(RpcValue.Text("b")))
      reply(responder, aSend, RpcValue.Flag(true))
      reply(responder, bSend, RpcValue.Flag(false))
      replies.expectMessage(CallResult(4, "speech.say", Right(Some(RpcValue.Flag(false)))))
      // An idempotent method sent this way still goes once: the deadline ends it, no retry follows.
      manualTime.timePasses(1.second)
      replies.expectMessageType[CallResult].result.left.toOption.get shouldBe a[RobotFailure.Timeout]
      outbox.expectNoMessage(Duration.Zero)
    }
    "let a newer command of a slot replace a waiting one (latest wins, a stop replaces a walk) and tell the replaced caller" in {
      val (_, outbox, responder, _) = fixture()
      val replies = createTestProbe[CallResult]()
      (1 to 4).foreach(i => RobotTestHooks.sendOnce(responder, say(s"$i")))
      val busy = (1 to 4).map(_ => outbox.expectMessageType[Outbox.Send])
      RobotTestHooks.sendOnce(responder, walk(0.1f), Some(replies.ref))
      RobotTestHooks.sendOnce(responder, head(0.1f), Some(replies.ref))
      RobotTestHooks.sendOnce(responder, walk(0.2f), Some(replies.ref))
      RobotTestHooks.sendOnce(responder, head(0.3f), Some(replies.ref))
      RobotTestHooks.sendOnce(responder, stop, Some(replies.ref), Priority.Safety)
      replies.receiveMessages(3).map(_.result) shouldBe Seq(
        Left(RobotFailure.Superseded(4, "motion.walk")), Left(RobotFailure.Superseded(4, "motion.head")),
        Left(RobotFailure.Superseded(4, "motion.walk")))
      // A safety call never waits, even with the robot's buffer full.
      val (s, stopSend) = sent(outbox)
      s.name shouldBe "motion.stop"
      stopSend.priority shouldBe Priority.Safety
      reply(responder, stopSend, RpcValue.Flag(true))
      replies.expectMessage(CallResult(4, "motion.stop", Right(Some(RpcValue.Flag(true)))))
      outbox.expectNoMessage(Duration.Zero)
      reply(responder, busy.head, RpcValue.Flag(true))
      sent(outbox)._1.params shouldBe head(0.3f).params
    }
    "count the heartbeat's probes, option commands and the robot's polls against the one in-flight cap" in {
      val (_, outbox, responder, sender) = fixture()
      val replies = createTestProbe[CallResult]()
      val probes = (1L to 4L).map(i => CallId(CallId.Owner.Heartbeat, i))
      probes.foreach(id =>
        sender ! NoResponseActor.Submit(Outbound.CallOut(probe(id)), Priority.Heartbeat, Some(id),
          NoResponseActor.Awaits.Reply(Some(500.millis))))
      (1 to 4).foreach(_ => sent(outbox)._1.name shouldBe "heartbeat.probe")
      // The buffer is full of probes: a caller's command and an option switch wait.
      RobotTestHooks.sendOnce(responder, say("later"), Some(replies.ref))
      // (The call reaches the sender through the response actor, which gives it its call id: let it reach the line
      // before the switch.)
      outbox.expectNoMessage(100.millis)
      val enable = DebuggingCommands(optionEnable = Some(DebuggingOptionNames(Seq("status"))))
      sender ! NoResponseActor.Submit(Outbound.DebugOut(enable), Priority.Debug, None, NoResponseActor.Awaits.Nothing)
      outbox.expectNoMessage(100.millis)
      // One probe answered: its room goes to the first in line.
      sender ! NoResponseActor.Finished(probes.head)
      sent(outbox)._1.params shouldBe Vector(RpcValue.Text("later"))
      outbox.expectNoMessage(100.millis)
      // The other probes were never answered: their hold ends, and the option switch goes (and frees its room at once).
      manualTime.timePasses(500.millis)
      val option = outbox.expectMessageType[Outbox.Send]
      MessageContents.decodeFrame(option.bytes).toOption.flatMap(_._2.debuggingCommands) shouldBe Some(enable)
      (1 to 3).foreach(i => RobotTestHooks.sendOnce(responder, say(s"$i")))
      (1 to 3).foreach(_ => outbox.expectMessageType[Outbox.Send])
    }
    "refuse what the waiting line cannot take with an error instead of dropping it silently" in {
      val (_, outbox, responder, _) = fixture()
      val replies = createTestProbe[CallResult]()
      (1 to 8).foreach(i => RobotTestHooks.sendOnce(responder, say(s"$i"), Some(replies.ref)))
      (1 to 4).foreach(_ => outbox.expectMessageType[Outbox.Send])
      replies.expectMessageType[CallResult].result shouldBe Left(RobotFailure.Overloaded(4,
          "4 calls in flight and 3 waiting"))
    }
    "answer each waiting command exactly once when stopped" in {
      val (_, outbox, responder, sender) = fixture()
      val replies = createTestProbe[CallResult]()
      (1 to 5).foreach(i => RobotTestHooks.sendOnce(responder, say(s"$i"), Some(replies.ref)))
      (1 to 4).foreach(_ => outbox.expectMessageType[Outbox.Send])
      // Nothing is answered while they wait; meanwhile the fifth, still in the responder's mailbox when the fourth went
      // out, reaches the waiting line (a responder stopped before would drop it unanswered: CI saw 4 of 5 once).
      replies.expectNoMessage(300.millis)
      testKit.stop(responder)
      testKit.stop(sender)
      replies.receiveMessages(5).foreach(_.result.left.toOption.get shouldBe a[RobotFailure])
      replies.expectNoMessage(200.millis)
    }
    "reach a ZeroMQ robot through the outbox: no FU-Remote header, behind the same competition gate" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val link = createTestProbe[ZeroMqRobotLink.Command]()
      val neverWritten: DatagramWriter = (_, _) => fail("a ZeroMQ robot's message went to the datagram socket")
      val outbox = spawn(Outbox(neverWritten, BudgetSettings(14000, 0, 1.0), competition = true))
      val outcomes = createTestProbe[Outbox.Outcome]()
      val sender = spawn(NoResponseActor(21, settings, robot.ref))
      robot.expectMessageType[RobotActor.RouteWanted]
      sender ! NoResponseActor.RouteChanged(RobotFrames.Route.ZeroMq(outbox, RobotStandIn.RobotAddress, link.ref))
      val poll = RpcCall("system", "ping", Vector.empty, Some(CallId(CallId.Owner.StatusPoll, 1)))
      def submit(): Unit = sender ! NoResponseActor.Submit(Outbound.CallOut(poll), Priority.Heartbeat, poll.callId,
        NoResponseActor.Awaits.Reply(Some(1.second)), Some(outcomes.ref))
      submit()
      val zeroMqSend = link.expectMessageType[ZeroMqRobotLink.Send]
      MessageContents.parse(zeroMqSend.bytes).toOption.flatMap(_.rpcRequest).map(RpcCall.fromProto) shouldBe Some(poll)
      sender ! NoResponseActor.Finished(poll.callId.get)
      outbox ! Outbox.GameStateChanged(GameState.Playing)
      submit()
      outcomes.fishForMessage(3.seconds) {
        case Outbox.RefusedByRule(_, rule) =>
          rule shouldBe Outbox.NoSendingWhileGameRuns
          akka.actor.testkit.typed.FishingOutcome.Complete
        case _ => akka.actor.testkit.typed.FishingOutcome.ContinueAndIgnore
      }
      link.expectNoMessage(100.millis)
    }
  }
}
