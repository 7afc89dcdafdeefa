package naogateway.gateway.robot

import java.net.InetSocketAddress

import akka.actor.testkit.typed.FishingOutcome
import akka.actor.testkit.typed.scaladsl.{ActorTestKit, TestProbe}
import akka.actor.typed.{ActorRef, Behavior}

import naogateway.wire.{HeaderForm, MessageContents, RpcCall}
import naogateway.gateway.CallSettings

/** What a test probe standing in for the robot actor answers to the call actors it serves. */
object RobotStandIn {

  /** The address the stand-in routes a robot's frames to (never sent to: the outbox is a probe). */
  val RobotAddress: InetSocketAddress = new InetSocketAddress("127.0.0.1", 1)

  /** The datagram route to `outbox`. */
  def route(outbox: ActorRef[Outbox.Command]): RobotFrames.Route =
    RobotFrames.Route.Datagrams(outbox, RobotAddress, HeaderForm.Legacy)

  /** Answers a call actor's start-up question about the robot's reachability. */
  def reachable(robot: TestProbe[RobotActor.FromChild], online: Boolean = true): Unit =
    robot.expectMessageType[RobotActor.ReachabilityWanted].replyTo ! online

  /** Answers the start-up questions of a sender and its response actor, in whichever order they come: the response
    * actor's reachability, and the sender's route to `outbox`.
    */
  def started(
      robot: TestProbe[RobotActor.FromChild], outbox: TestProbe[Outbox.Command], online: Boolean = true): Unit = {
    var left = 2
    robot.fishForMessage(robot.remainingOrDefault) {
      case RobotActor.ReachabilityWanted(r) =>
        r ! online
        left -= 1
        if (left == 0) FishingOutcome.Complete else FishingOutcome.Continue
      case RobotActor.RouteWanted(r) =>
        r ! NoResponseActor.RouteChanged(route(outbox.ref))
        left -= 1
        if (left == 0) FishingOutcome.Complete else FishingOutcome.Continue
      case other => FishingOutcome.Fail(s"unexpected $other")
    }
    ()
  }

  /** A robot's call actors as its robot actor spawns them, `robot` standing in for it: the sender first, then the
    * response actor (`wrap` puts a test's supervision around either), both started and routed to `outbox`.
    */
  def callActors(kit: ActorTestKit, robotId: Int, settings: CallSettings, robot: TestProbe[RobotActor.FromChild],
      outbox: TestProbe[Outbox.Command], online: Boolean = true,
      wrapSender: Behavior[NoResponseActor.Command] => Behavior[NoResponseActor.Command] = identity,
      wrapResponder: Behavior[Any] => Behavior[Any] = identity): (ActorRef[Any], ActorRef[NoResponseActor.Command]) = {
    val sender = kit.spawn(wrapSender(NoResponseActor(robotId, settings, robot.ref)))
    val responder = kit.spawn(wrapResponder(ResponseActor(robotId, settings, robot.ref, sender, online = true)))
    started(robot, outbox, online)
    (responder, sender)
  }

  /** The call in an outbox `Send` from a robot's sender. */
  def callIn(send: Outbox.Send): RpcCall =
    MessageContents.decodeFrame(send.bytes).toOption.flatMap(_._2.rpcRequest).map(RpcCall.fromProto)
      .getOrElse(throw new AssertionError(s"no call in the datagram to ${send.to}"))

  /** The next datagram a robot's sender sent, with its call. */
  def sent(outbox: TestProbe[Outbox.Command]): (RpcCall, Outbox.Send) = {
    val send = outbox.expectMessageType[Outbox.Send]
    (callIn(send), send)
  }
}
