package naogateway.actors

import java.net.InetSocketAddress

import akka.actor.testkit.typed.scaladsl.TestProbe

import naogateway.wire.{HeaderForm, MessageContents, RpcCall}
import naogateway.{Outbox, ResponseActor, RobotActor}

/** What a test probe standing in for the robot actor answers to the call actors it serves. */
object RobotStandIn {

  /** The address the stand-in routes a response actor's calls to (never sent to: the outbox is a probe). */
  val RobotAddress: InetSocketAddress = new InetSocketAddress("127.0.0.1", 1)

  /** Answers a call actor's start-up question about the robot's reachability. */
  def reachable(robot: TestProbe[RobotActor.FromChild], online: Boolean = true): Unit =
    robot.expectMessageType[RobotActor.ReachabilityWanted].replyTo ! online

  /** Answers a response actor's start-up questions: reachability, then its route to `outbox`. */
  def started(robot: TestProbe[RobotActor.FromChild], outbox: TestProbe[Outbox.Command], online: Boolean = true): Unit = {
    reachable(robot, online)
    robot.expectMessageType[RobotActor.RouteWanted].replyTo ! ResponseActor.RouteChanged(
      ResponseActor.Route.Datagrams(outbox.ref, RobotAddress, HeaderForm.Legacy))
  }

  /** The call in an outbox `Send` from a response actor. */
  def callIn(send: Outbox.Send): RpcCall =
    MessageContents.decodeFrame(send.bytes).toOption.flatMap(_._2.rpcRequest).map(RpcCall.fromProto)
      .getOrElse(throw new AssertionError(s"no call in the datagram to ${send.to}"))

  /** The next datagram a response actor sent, with its call. */
  def sent(outbox: TestProbe[Outbox.Command]): (RpcCall, Outbox.Send) = {
    val send = outbox.expectMessageType[Outbox.Send]
    (callIn(send), send)
  }
}
