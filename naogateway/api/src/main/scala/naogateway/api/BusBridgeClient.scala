package naogateway.api

/** The gateway's bus bridge (docs/protocol.md 6.9) tells the middleware's lease holder that a tool connected to robot
  * `robotId`'s bridge (`connected`) or left it, so the robot's actuator leases are taken and given back with it.
  */
final case class BusBridgeClient(robotId: Int, connected: Boolean)
