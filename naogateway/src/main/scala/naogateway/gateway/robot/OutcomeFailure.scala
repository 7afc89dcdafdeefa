package naogateway.gateway.robot

import naogateway.api.RobotFailure

/** What an outbox outcome means for the call it carried: the gateway's side of `RobotFailure` (api). */
private[naogateway] object OutcomeFailure {

  /** The failure an outbox outcome means for the call it carried, if any (`Accepted` is none). */
  def of(robotId: Int, outcome: Outbox.Outcome): Option[RobotFailure] = outcome match {
    case Outbox.Accepted(_)            => None
    case Outbox.RefusedByRule(_, rule) => Some(RobotFailure.RuleGate(rule))
    case Outbox.Dropped(_, reason)     => Some(RobotFailure.Overloaded(robotId, reason))
  }
}
