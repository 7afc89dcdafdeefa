package naogateway.integration

import scala.concurrent.Await
import scala.concurrent.duration._

import akka.actor.typed.scaladsl.AskPattern._
import akka.actor.typed.{ActorRef, ActorSystem}
import akka.util.Timeout

import naogateway.wire.stream.StreamStats
import naogateway.access.GatewayAccess
import naogateway.gateway.Gateway
import naogateway.gateway.robot.{RobotActor, RobotEffects, StreamActor}

/** What the gateway's own specs reach past its public protocol ([[naogateway.access.GatewayAccess]]): the gateway's own
  * protocol on the ref its spawner holds, a robot actor and its children; and, for specs and benches outside the
  * gateway's package, a robot's secure stream, whose messages are the gateway's own.
  */
object GatewayInternals {

  /** How long each question here waits: a robot is connected once it answered a probe. */
  private implicit val timeout: Timeout = 10.seconds

  /** The gateway's own protocol on `gateway`: the one actor takes both (its public messages are wrapped on arrival). */
  private[naogateway] def own(gateway: ActorRef[GatewayAccess.Command]): ActorRef[Gateway.Command] =
    gateway.unsafeUpcast[Any]

  /** The robot actor of `robotId` with its whole protocol, if the gateway knows the robot. */
  private[naogateway] def robotActor(gateway: ActorRef[GatewayAccess.Command], robotId: Int)(implicit
      system: ActorSystem[_]): Option[ActorRef[RobotActor.Command]] =
    Await.result(own(gateway).ask[Option[ActorRef[RobotActor.Command]]](Gateway.GetRobot(robotId, _)), timeout.duration)

  /** The children of robot `robotId` once it is reachable, if the gateway knows the robot. */
  private[naogateway] def connect(gateway: ActorRef[GatewayAccess.Command], robotId: Int)(implicit
      system: ActorSystem[_]): Option[RobotEffects.Connected] =
    robotActor(gateway, robotId).map(r =>
      Await.result(r.ask[RobotEffects.Connected](RobotActor.Connect(_)), timeout.duration))

  /** Robot `robotId`'s secure stream once the robot is reachable, if the gateway knows the robot. */
  def stream(gateway: ActorRef[GatewayAccess.Command], robotId: Int)(implicit
      system: ActorSystem[_]): Option[TestStream] =
    connect(gateway, robotId).map(c => new TestStream(c.stream))
}

/** One robot's secure stream as a spec outside the gateway's package drives it. */
final class TestStream private[naogateway] (endpoint: ActorRef[StreamActor.Command]) {

  /** Sends `payload` reliably. */
  def send(payload: Array[Byte]): Unit = endpoint ! StreamActor.Send(payload)

  /** Delivers every payload received from the robot, in order, to `subscriber`. */
  def subscribe(subscriber: ActorRef[StreamActor.Received]): Unit = endpoint ! StreamActor.Subscribe(subscriber)

  /** Answers `replyTo` with the stream's figures. */
  def stats(replyTo: ActorRef[StreamStats]): Unit = endpoint ! StreamActor.GetStats(replyTo)
}
