package naogateway.actors

import akka.actor.testkit.typed.scaladsl.TestProbe

import naogateway.RobotActor

/** What a test probe standing in for the robot actor answers to the call actors it serves. */
object RobotStandIn {

  /** Answers a call actor's start-up question about the robot's reachability. */
  def reachable(robot: TestProbe[RobotActor.FromChild], online: Boolean = true): Unit =
    robot.expectMessageType[RobotActor.ReachabilityWanted].replyTo ! online
}
