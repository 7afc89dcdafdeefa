package naogateway.gateway.robot

import akka.actor.typed.{ActorRef, ActorSystem}

import naogateway.access.RobotAccess
import naogateway.api.{CallResult, Priority}
import naogateway.gateway.robot.RobotEffects.Connected
import naogateway.wire.RpcCall

/** What specs do to the robot's centre and production never does, in one place, so that no actor's protocol carries a
  * message that only a spec sends: a call sent exactly once, and the failures the restart specs inject into each child.
  */
private[naogateway] object RobotTestHooks {

  /** Sends `call` once, never retried whatever its method, through the robot's response actor `calls` and the robot's
    * one order like any caller's call; `replyTo`, when given, learns how it ended, else its answer is dropped.
    */
  def sendOnce(calls: ActorRef[RobotAccess.Call], call: RpcCall, replyTo: Option[ActorRef[CallResult]] = None,
      priority: Priority = Priority.Command)(implicit system: ActorSystem[_]): Unit =
    calls ! RobotAccess.Call(call, replyTo.getOrElse(system.ignoreRef[CallResult]), priority, idempotent = Some(false))

  /** Makes the robot's sender fail as a bug would: a null route, on which its next transmission throws once (the
    * restarted sender asks the robot actor for the route again).
    */
  def crashSender(children: Connected): Unit = children.noResponse ! NoResponseActor.RouteChanged(null)

  /** Makes the robot's vision actor fail as a bug would: a null registration list. */
  def crashVision(children: Connected): Unit = children.vision ! VisionActor.Subscribers(null)

  /** Makes the robot's stream actor fail as a bug would: a null reply ref. */
  def crashStream(children: Connected): Unit = children.stream ! StreamActor.GetStats(null)
}
