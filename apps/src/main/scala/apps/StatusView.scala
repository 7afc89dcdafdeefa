package apps

import naogateway.{LinkStats, Outbox, RobotSnapshot}
import naogateway.wire.gamecontroller.GameControlData

/** What the launcher shows: robots, their links, the team's traffic and the game. */
final case class StatusModel(
    robots: Vector[RobotSnapshot],
    links: Map[Int, LinkStats],
    traffic: Option[Outbox.TrafficStats],
    game: Option[GameControlData]
)

/** Rendering of the live status: a table for terminals, and plain change lines for logs and pipes. */
object StatusView {

  private def opt[A](a: Option[A])(f: A => String): String = a.fold("-")(f)

  /** One line describing a robot, as both the table and the plain lines use it. */
  def robotLine(r: RobotSnapshot, link: Option[LinkStats]): String = {
    val rtt = link.flatMap(_.rttMillis)
    val loss = link.map(_.lossEstimate)
    f"robot ${r.robotId}%-3d ${if (r.online) "online " else "offline"} ${r.quality.name}%-8s " +
      f"battery ${opt(r.batteryVoltage)(v => f"$v%.2f V")}%-8s posture ${opt(r.posture)(identity)}%-8s " +
      f"role ${opt(r.role)(identity)}%-9s rtt ${opt(rtt)(v => f"$v%.1f ms")}%-9s loss ${opt(loss)(v => f"${v * 100}%.0f %%")}%-5s " +
      s"${r.address.getAddress.getHostAddress}:${r.address.getPort}"
  }

  /** The full screen for a terminal. */
  def render(model: StatusModel): Vector[String] = {
    val traffic = model.traffic.fold("team traffic: -") { t =>
      f"team traffic: out ${t.outBytesLastSecond / 1000.0}%.1f kB/s, in ${t.inBytesLastSecond / 1000.0}%.1f kB/s, " +
        f"${t.teamLoad * 100}%.0f %% of ${t.budgetBytesPerSecond / 1000} kB/s" +
        (if (t.refusedByRule > 0) s", ${t.refusedByRule} refused by the competition rule" else "")
    }
    val game = model.game.fold("game: no GameController heard") { g =>
      s"game: ${g.gameState} (${if (g.firstHalf) "first" else "second"} half, ${g.secsRemaining} s left, " +
        s"${g.team0.teamNumber} ${g.team0.score} : ${g.team1.score} ${g.team1.teamNumber})"
    }
    val online = model.robots.count(_.online)
    Vector(s"naogateway - ${model.robots.size} robot(s), $online online", traffic, game, "") ++
      model.robots.map(r => robotLine(r, model.links.get(r.robotId))) ++ Vector("", "Ctrl-C stops everything.")
  }

  /** Plain lines for what changed between two models: a robot's online state or posture. */
  def changes(before: StatusModel, after: StatusModel): Vector[String] = {
    val old = before.robots.map(r => r.robotId -> r).toMap
    after.robots.flatMap { r =>
      old.get(r.robotId) match {
        case Some(o) if o.online == r.online && o.posture == r.posture => None
        case Some(o) if o.online == r.online && !r.online               => None
        case None if !r.online                                           => None
        case _                                                           => Some(robotLine(r, after.links.get(r.robotId)))
      }
    }
  }
}
