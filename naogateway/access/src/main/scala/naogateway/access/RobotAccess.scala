package naogateway.access

import scala.concurrent.duration.FiniteDuration

import akka.actor.typed.ActorRef

import naogateway.wire.RpcCall
import naogateway.api.{CallResult, LinkStats, Priority, RobotSnapshot, VisionFrame}

/** One robot as the middleware may use it (from [[GatewayAccess.GetRobotAccess]]): questions and [[RobotAccess.Open]]
  * to its robot actor; once open, calls to its response actor and camera registrations to its vision actor. Nothing
  * that feeds the actors frames, refusals, re-bindings or subscribers; no way to the robot's sender. How the gateway
  * takes these messages without an extra hop: [[GatewayAccess]].
  */
object RobotAccess {

  /** What the middleware may send a robot actor. */
  sealed trait Command

  /** Answers with [[Opened]] once the robot is reachable (probing it first if needed; waits while it is not). */
  final case class Open(replyTo: ActorRef[Opened]) extends Command

  /** A question the robot actor answers at once, reachable or not. */
  sealed trait Question extends Command

  /** Answers with the latest keep-alive contents and liveness. */
  final case class GetSnapshot(replyTo: ActorRef[RobotSnapshot]) extends Question

  /** Answers with the link figures. */
  final case class GetLinkStats(replyTo: ActorRef[LinkStats]) extends Question

  /** A reachable robot as the middleware may use it: calls through its response actor, camera registrations through its
    * vision actor. Both refs die with a restart of the robot actor: the holder's cue to open again.
    */
  final case class Opened(robotId: Int, response: ActorRef[Call], vision: ActorRef[RegisterVision])

  /** Calls the robot; `replyTo` gets exactly one `CallResult`. `timeout` overrides the configured one; `idempotent`
    * overrides the method table's word on whether the call may be sent again (`Some(false)`: no retries).
    */
  final case class Call(
      call: RpcCall,
      replyTo: ActorRef[CallResult],
      priority: Priority = Priority.Command,
      timeout: Option[FiniteDuration] = None,
      idempotent: Option[Boolean] = None
  )

  /** Registers a subscriber's stream of camera frames; `grid` asks for grid frames too (they are large, ~790 bytes
    * each). The robot actor keeps the registrations, so they outlive a restart of the vision actor.
    */
  final case class RegisterVision(subscriber: ActorRef[VisionFrame], grid: Boolean)
}
