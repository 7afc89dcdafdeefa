package robotmiddleware

import naogateway.api.RobotFailure

/** How apps are told of a call that a newer one replaced or a restart interrupted: as an overload to retry, the one
  * error type, in words for apps. Applied by the guard to the answers it relays and by `RobotInterface` to those the
  * robot's command owner sends an app directly.
  */
private[robotmiddleware] object AppFailure {

  /** `error` as an app sees it. */
  def apply(robotId: Int, error: RobotFailure): RobotFailure = error match {
    case RobotFailure.Superseded(_, call)  => RobotFailure.Overloaded(robotId, s"$call replaced by a newer one")
    case RobotFailure.Interrupted(_, call) => RobotFailure.Overloaded(robotId, s"$call interrupted, try again")
    case other                             => other
  }
}
