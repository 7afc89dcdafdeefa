package apps

import naogateway.api.{ClockEstimate, LinkQuality, LinkStats, RobotSnapshot, SigningState}
import naogateway.wire.{Posture, RobotReport}
import robotmiddleware.ServoLimits

/** What every status view shows of one robot (the launcher's status lines, robotctl's `status`, the web view's cards):
  * the one mapping from a robot's snapshot and link figures to shown values, so the views cannot disagree. The robot's
  * own part is its [[RobotReport]], as its keep-alive said it. Total over whatever a snapshot holds: a missing address
  * or quality, and a figure that is not finite (NaN, infinite), become `None`, which each view shows its way.
  */
final case class RobotRow(
    robotId: Int,
    address: Option[String],
    online: Boolean,
    quality: Option[LinkQuality],
    report: RobotReport,
    rttMillis: Option[Double],
    loss: Option[Double],
    clock: Option[ClockEstimate],
    refused: Map[String, Long],
    signing: SigningState = SigningState.Off
) {

  /** The link as shown: `online`, `unsigned` (a robot that must sign heard only with unsigned or badly signed frames:
    * there, but nothing of it counts), or `offline`.
    */
  def linkState: String =
    if (online) "online" else if (signing == SigningState.Unsigned) SigningState.Unsigned.name else "offline"

  /** The battery voltage, when reported and finite. */
  def battery: Option[Double] = report.batteryVoltage.filter(RobotRow.finite)

  /** The posture the robot reported. */
  def posture: Option[Posture] = report.posture
}

/** Building rows. */
object RobotRow {

  private def finite(d: Double): Boolean = !d.isNaN && !d.isInfinite

  /** The compact mark of robot `r`'s servos worth a warning by `limits` (`robotmiddleware.servos`), as the status views
    * append it: `SERVOS hot 3,7 low-voltage 2`; None while none is (or before the first servo telemetry).
    */
  def servoMark(r: RobotSnapshot, limits: ServoLimits): Option[String] = {
    val readings = r.servos.fold(Vector.empty[naogateway.api.ServoReading])(_.servos)
    def ids(name: String, marked: naogateway.api.ServoReading => Boolean) =
      Some(readings.filter(marked).map(_.id)).filter(_.nonEmpty).map(i => s"$name ${i.mkString(",")}")
    val parts = Vector(ids("hot", limits.hot), ids("low-voltage", limits.lowVoltage)).flatten
    Option.when(parts.nonEmpty)(("SERVOS" +: parts).mkString(" "))
  }

  /** The row of robot `r` with its link figures `link`; the clock estimate is the link figures', else the snapshot's.
    */
  def of(r: RobotSnapshot, link: Option[LinkStats]): RobotRow = RobotRow(
    r.robotId,
    // The IP address when the robot's address is resolved (the gateway knows robots by IP), else the name it was given.
    Option(r.address).map(a =>
      s"${Option(a.getAddress).map(_.getHostAddress).orElse(Option(a.getHostString)).getOrElse("-")}:${a.getPort}"),
    r.online,
    // An unsigned robot's frames are all refused: it has no link quality to show, only its `unsigned` state.
    Option(r.quality).filterNot(_ => !r.online && r.signing == SigningState.Unsigned),
    r.report,
    link.flatMap(_.rttMillis).filter(finite),
    link.map(_.lossEstimate).filter(finite),
    link.flatMap(_.clock).orElse(r.clock),
    link.fold(Map.empty[String, Long])(_.rejected),
    r.signing
  )
}
