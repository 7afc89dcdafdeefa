package naogateway.api

/** The team's traffic: bytes in the last second each way, the budget, queues and counters, and the competition gate.
  *
  * @param gameRunning
  *   whether the gate's reading closes it: the GameController last said READY, SET or PLAYING, or its last packet could
  *   not be read
  * @param competition
  *   whether the competition rule applies (`naogateway.competition.enabled`)
  * @param gateReason
  *   why the gate's reading closes it (`CompetitionGate.why`)
  */
final case class TrafficStats(
    outBytesLastSecond: Long,
    inBytesLastSecond: Long,
    budgetBytesPerSecond: Int,
    queued: Map[String, Int],
    datagramsOut: Long,
    datagramsIn: Long,
    refusedByRule: Long,
    dropped: Long,
    gameRunning: Boolean,
    competition: Boolean,
    gateReason: Option[String] = None
) {

  /** Whether the outbox sends to robots now: closed only in competition mode while the game runs. */
  def gateOpen: Boolean = !(competition && gameRunning)

  /** Two-way traffic as a share of the budget. */
  def teamLoad: Double = (outBytesLastSecond + inBytesLastSecond).toDouble / budgetBytesPerSecond
}
