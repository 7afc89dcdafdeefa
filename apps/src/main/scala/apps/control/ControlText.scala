package apps.control

import naogateway.api.RobotFailure

import naogateway.api.{LinkStats, RobotSnapshot}
import robotmiddleware.RobotHolds

/** What robotctl prints, from what the control port reads: the status table's lines, a robot's servo table, the
  * doctor's lines for the middleware's holds and the text of a failure. Pure, so each is tested without a server.
  */
object ControlText {

  /** The doctor's lines for the middleware's holds. */
  def holdFindings(holds: Vector[RobotHolds]): Vector[Finding] = {
    val held = holds.collect { case RobotHolds(id, _, Some(reason)) => id -> reason }
    if (held.isEmpty) Vector(Finding("safety", "no robot is held safe", problem = false))
    else
      held.map { case (id, reason) =>
        Finding(
          "safety",
          s"robot $id is held safe, motion refused: $reason",
          problem = true,
          s"swap or charge robot $id's battery; the hold ends by itself once it reads full enough " +
            s"(simulated: robotctl battery $id swap)"
        )
      }
  }

  /** The text of a failure, as robotctl prints it. */
  def errorText(e: Throwable): String = e match {
    case f: RobotFailure => f.getMessage
    case other           => Option(other.getMessage).filter(_.nonEmpty).getOrElse(other.getClass.getSimpleName)
  }

  /** The column heads of [[statusLine]]. */
  val statusHeader: String =
    f"${"id"}%-4s ${"address"}%-22s ${"state"}%-8s ${"link"}%-9s ${"battery"}%-8s ${"posture"}%-8s ${"role"}%-9s " +
      f"${"rtt"}%-9s ${"loss"}%-6s ${"clock"}%-10s ${"drift"}%-9s leases"

  /** One line per robot: id, address, online (or `unsigned`, RobotRow.linkState), link quality, battery, posture, role,
    * round-trip time, loss, and the robot's clock against the gateway's (the error bound of its estimate, and its
    * drift: `settling` until its bound is within `ClockEstimate.SettledDriftPpm`; `-` until there is an estimate),
    * which app holds which lease (`walk=teleop head=zeromq`, `-` for none) and `HELD SAFE` while the middleware holds
    * the robot safe; `development build` after a robot running one; its hot or low-voltage servos by `limits` (`SERVOS
    * hot 3 low-voltage 2`, [[apps.RobotRow.servoMark]]).
    */
  def statusLine(r: RobotSnapshot, stats: Option[LinkStats], holds: Option[RobotHolds] = None,
      limits: robotmiddleware.ServoLimits = robotmiddleware.ServoLimits()): String = {
    val row = apps.RobotRow.of(r, stats)
    val rtt = row.rttMillis.fold("-")(v => f"$v%.1f ms")
    val loss = row.loss.fold("-")(v => f"${v * 100}%.0f %%")
    val clock = row.clock.fold("-")(c => f"±${c.errorBoundMillis}%.1f ms")
    val drift = row.clock.fold("-")(c => if (c.driftSettled) f"${c.driftPpm}%+.0f ppm" else "settling")
    f"${row.robotId}%-4d ${row.address.getOrElse("-")}%-22s ${row.linkState}%-8s " +
      f"${row.quality.fold("-")(_.name)}%-9s ${row.battery.fold("-")(v => f"$v%.2f V")}%-8s " +
      f"${row.posture.fold("-")(_.name)}%-8s " +
      f"${row.report.role.fold("-")(naogateway.api.Printable.text)}%-9s $rtt%-9s $loss%-6s $clock%-10s $drift%-9s " +
      holds.fold("-")(h => naogateway.api.Printable.text(h.describeLeases)) +
      (if (holds.exists(_.safetyHold.isDefined)) " HELD SAFE" else "") +
      (if (row.report.development) " development build" else "") +
      apps.RobotRow.servoMark(r, limits).fold("")(" " + _)
  }

  /** A robot's servo table (docs/protocol.md 6.8) at `now` (the gateway's `System.nanoTime`): a line saying how old it
    * is, then one line per servo (id, position raw and in degrees, load, voltage, temperature), `silent`, `HOT`, `LOW
    * VOLTAGE` and a servo's error byte marked; one line saying so when the robot has sent none.
    */
  def servoLines(r: RobotSnapshot, limits: robotmiddleware.ServoLimits, now: Long): List[String] =
    r.servos match {
      case None => List(s"robot ${r.robotId}: no servo telemetry" + (if (r.online) " yet" else " (offline)"))
      case Some(t) =>
        val age = math.max(0L, now - t.receivedAtNanos) / 1000000L
        s"robot ${r.robotId}: ${t.servos.size} servos, read $age ms ago" +
          t.busErrors.fold("")(n => s", $n bus errors since power-up") ::
          f"${"id"}%-4s ${"position"}%-14s ${"load"}%-6s ${"voltage"}%-8s ${"temp"}%-6s" ::
          t.servos.toList.map { servo =>
            if (servo.silent) f"${servo.id}%-4d silent"
            else {
              val position = servo.position.fold("-")(p => p.toString + servo.degrees.fold("")(d => f" ($d%+.0f°)"))
              val marks = Vector(
                Option.when(limits.hot(servo))("HOT"),
                Option.when(limits.lowVoltage(servo))("LOW VOLTAGE"),
                Option.when(servo.error != 0)(f"error 0x${servo.error}%02x")
              ).flatten
              f"${servo.id}%-4d $position%-14s ${servo.load.fold("-")(_.toString)}%-6s " +
                f"${servo.voltage.fold("-")(v => f"$v%.1f V")}%-8s ${servo.temperature.fold("-")(c => s"$c °C")}%-6s" +
                (if (marks.isEmpty) "" else marks.mkString(" ", ", ", ""))
            }
          }
    }
}
