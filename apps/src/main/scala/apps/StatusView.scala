package apps

import naogateway.api.{GameSource, GatewayStats, LinkStats, Printable, RobotSnapshot, SigningState, TrafficStats}
import robotmiddleware.ServoLimits
import naogateway.wire.gamecontroller.{
  ControlData2014,
  GameControlData,
  GamePhase,
  GameState,
  HlControlData,
  HlSecondaryState,
  HslGameData,
  PlayerPenalty,
  SecondaryGameState,
  SetPlay
}

/** What the launcher shows: robots, their links, the team's traffic with the competition gate, and the game;
  * `servoLimits` says which servos are marked (`robotmiddleware.servos`).
  */
final case class StatusModel(
    robots: Vector[RobotSnapshot],
    links: Map[Int, LinkStats],
    traffic: Option[TrafficStats],
    game: Option[GameControlData],
    gameSource: Option[GameSource] = None,
    gateway: Option[GatewayStats] = None,
    servoLimits: ServoLimits = ServoLimits()
)

/** Constructors of status models. */
object StatusModel {

  /** Nothing heard yet. */
  val empty: StatusModel = StatusModel(Vector.empty, Map.empty, None, None)
}

/** Rendering of the live status: a screen for terminals, and plain change lines for logs and pipes. Every function here
  * is total: whatever a model holds, it renders (a value it cannot show becomes "-"), so the printer never dies on a
  * packet it did not expect.
  */
object StatusView {

  private def opt[A](a: Option[A])(f: A => String): String = a.fold("-")(f)

  /** A number that is not finite shows as "-" rather than as "NaN" or "Infinity". */
  private def finite(d: Double)(f: Double => String): String = if (d.isNaN || d.isInfinite) "-" else f(d)

  /** The GameController's penalty of robot `r` in `game`: the robot is player number `robotId` of the team its
    * keep-alive names (docs/protocol.md 10.11).
    */
  def penalty(r: RobotSnapshot, game: Option[GameControlData]): Option[PlayerPenalty] =
    for {
      g <- game
      team <- r.teamId
      p <- g.penaltyOf(team, r.robotId)
    } yield p

  /** One line describing a robot (its [[RobotRow]]), as both the screen and the plain lines use it, with its penalty
    * when the GameController has taken it off the game and its hot or low-voltage servos by `limits`
    * ([[RobotRow.servoMark]]).
    */
  def robotLine(r: RobotSnapshot, link: Option[LinkStats], game: Option[GameControlData] = None,
      limits: ServoLimits = ServoLimits()): String = {
    val row = RobotRow.of(r, link)
    f"robot ${row.robotId}%-3d ${row.linkState}%-7s ${opt(row.quality)(_.name)}%-8s " +
      f"battery ${opt(row.battery)(v => f"$v%.2f V")}%-8s posture ${opt(row.posture)(_.name)}%-8s " +
      f"role ${opt(row.report.role)(Printable.text)}%-9s rtt ${opt(row.rttMillis)(v => f"$v%.1f ms")}%-9s " +
      f"loss ${opt(row.loss)(v => f"${v * 100}%.0f %%")}%-5s " + row.address.getOrElse("-") +
      (if (row.report.development) " development build" else "") +
      penalty(r, game).fold("")(p => s" PENALISED: ${p.describe}") +
      RobotRow.servoMark(r, limits).fold("")(" " + _)
  }

  /** The game state as the GameController's display names it: PLAYING, READY, ... */
  def stateName(state: GameState): String = state match {
    case GameState.Unknown(code) => s"UNKNOWN($code)"
    case known                   => known.toString.toUpperCase
  }

  /** What a version says beside the main state, in words: the phase (shoot-out, extra time, time-out), the set play,
    * and in versions 20 and 19 whether play is stopped. Empty in regular play.
    */
  def situation(game: GameControlData): Vector[String] = game match {
    case g: ControlData2014 =>
      Vector(g.secondaryGameState).filter(_ != SecondaryGameState.Normal).map(words)
    case g: HlControlData =>
      Vector(g.secondaryState).filter(_ != HlSecondaryState.Normal).map(words)
    case g: HslGameData =>
      Vector(g.gamePhase).filter(_ != GamePhase.Normal).map(words) ++
        Vector(g.setPlay).filter(_ != SetPlay.NoSetPlay).map(words) ++ Option.when(g.stopped)("stopped").toVector
  }

  /** A code's name in words: `GoalKick` is "goal kick", `Unknown(9)` "unknown(9)". */
  private def words(value: Any): String = value.toString.replaceAll("([a-z])([A-Z])", "$1 $2").toLowerCase

  /** The game in one line: version, state, half, seconds remaining, secondary clock where it counts, score. */
  def gameLine(game: Option[GameControlData]): String = game.fold("game: no GameController heard") { g =>
    val extra = situation(g)
    val secondaryState = if (extra.isEmpty) "" else extra.mkString(" (", ", ", ")")
    // The secondary clock counts the ready phase, a time-out, a penalty shot...; 0 means it is not running.
    val secondary = g.secondaryClock.filter(_ > 0).fold("")(t => s", secondary $t s")
    s"game: ${stateName(g.gameState)}$secondaryState, ${if (g.firstHalf) "first" else "second"} half, " +
      s"${g.secsRemaining} s left$secondary, score ${g.team0.score} : ${g.team1.score} " +
      s"(team ${g.team0.teamNumber} : team ${g.team1.teamNumber}), version ${g.version.number}"
  }

  /** What a gate reason says, without its figures (in parentheses); "the game is running" and "opening once the game
    * has not run for a while" are one kind, so forged packets flipping between them print no line per packet.
    */
  private def kind(reason: Option[String]): Option[String] = reason.map(_.takeWhile(_ != '(').trim).map {
    case r if r.startsWith("opening once") || r.startsWith("the game is running") => "the game"
    case r                                                                        => r
  }

  /** The team's message budget and every warning (a second GameController, the budget), each on a line of its own. */
  def sourceLines(source: GameSource): Vector[String] =
    source.budget.toVector ++ source.warnings.map(w => s"WARNING: $w")

  /** In the monitor role: the age of the true state, and each robot's status message as the GameController forwarded it
    * (fallen, pose, ball age), shown beside the gateway's own robot lines.
    */
  def monitorLines(source: GameSource): Vector[String] =
    source.trueStateAgeMillis
      .map(ms => f"true game state from the GameController (monitor), ${ms / 1000.0}%.1f s old")
      .toVector ++
      source.forwarded.map { f =>
        val s = f.status
        val ball = if (s.ballAge < 0) "ball never seen" else f"ball seen ${s.ballAge}%.1f s ago"
        f"GameController hears team ${s.team} player ${s.player} (${f.from.getHostAddress}): " +
          f"${if (s.fallen) "fallen" else "up"}, pose ${s.pose._1}%.0f ${s.pose._2}%.0f mm ${s.pose._3}%.2f rad, $ball"
      }

  /** The competition gate in one line. */
  def gateLine(traffic: Option[TrafficStats]): String = traffic.fold("competition gate: -") { t =>
    if (!t.competition) "competition gate: open (competition rule off)"
    else if (t.gateOpen) "competition gate: open"
    else s"competition gate: CLOSED: ${t.gateReason.getOrElse("the game is running")}: nothing is sent to the robots"
  }

  /** The team's traffic against the budget in one line. */
  def trafficLine(traffic: Option[TrafficStats]): String = traffic.fold("team traffic: -") { t =>
    val load = if (t.budgetBytesPerSecond > 0) finite(t.teamLoad * 100)(v => f"$v%.0f %%") else "-"
    f"team traffic: out ${t.outBytesLastSecond / 1000.0}%.1f kB/s, in ${t.inBytesLastSecond / 1000.0}%.1f kB/s, " +
      f"$load of the ${t.budgetBytesPerSecond / 1000.0}%.1f kB/s budget" +
      (if (t.refusedByRule > 0) s", ${t.refusedByRule} refused by the competition rule" else "") +
      (if (t.dropped > 0) s", ${t.dropped} dropped" else "")
  }

  /** The recording's figures (docs/recording.md), or the replay's, with the tap's readers that dropped entries; nothing
    * when none of these has anything to say.
    */
  def recordingLine(stats: Option[GatewayStats]): Option[String] = stats.flatMap { g =>
    g.replay.map { r =>
      s"replay: ${r.fed} datagrams fed, ${r.discarded} outbound discarded" + (if (r.finished) ", finished" else "")
    }.orElse(Option.when(g.recording.enabled) {
      val r = g.recording
      s"recording: ${r.messages} messages in ${r.files} file(s), ${r.dropped} dropped" +
        (if (r.failed > 0) s", ${r.failed} failed" else "") + r.currentFile.fold("")(f =>
          s", now ${f.split('/').last}") +
        r.retention.fold("")(k => s"; ${k.describe}")
    }) match {
      case Some(line)             => Some(line + behind(g).fold("")("; " + _))
      case None if g.tap.nonEmpty => behind(g).map("tap: " + _)
      case None                   => None
    }
  }

  /** The tap's readers that fell behind (docs/architecture.md, the tap), e.g. "foxglove-feed dropped 12". */
  private def behind(g: GatewayStats): Option[String] =
    Option(g.tap.filter(_.dropped > 0).map(r => s"${r.reader} dropped ${r.dropped}")).filter(_.nonEmpty)
      .map(_.mkString(", "))

  /** The full screen for a terminal. */
  def render(model: StatusModel): Vector[String] = {
    val online = model.robots.count(_.online)
    Vector(s"naogateway - ${model.robots.size} robot(s), $online online", gameLine(model.game)) ++
      model.gameSource.map(_.describe).toVector ++ model.gameSource.toVector.flatMap(sourceLines) ++ Vector(
        gateLine(model.traffic),
        trafficLine(model.traffic)) ++ recordingLine(model.gateway).toVector ++ Vector("") ++
      model.robots.map(r => robotLine(r, model.links.get(r.robotId), model.game, model.servoLimits)) ++ model.gameSource
        .toVector.flatMap(
          monitorLines) ++
      Vector("", "Ctrl-C stops everything.")
  }

  /** `lines` cut to a screen of `columns` × `rows`: long lines are cut (a wrapped line would shift the redrawn screen),
    * and when rows run out the last one says how many lines are not shown.
    */
  def fit(lines: Vector[String], columns: Int, rows: Int): Vector[String] = {
    val cols = math.max(columns, 1)
    val shown =
      if (rows <= 0) Vector.empty
      else if (lines.size <= rows) lines
      else lines.take(rows - 1) :+ s"... ${lines.size - rows + 1} more line(s); a taller terminal shows them"
    shown.map(l => if (l.length > cols) l.take(cols) else l)
  }

  /** Plain lines for what changed between two models: a robot's online state, posture, `unsigned` state or servo mark,
    * the game state (not every packet), and the competition gate.
    */
  def changes(before: StatusModel, after: StatusModel): Vector[String] = {
    val old = before.robots.map(r => r.robotId -> r).toMap
    // A penalty is news when it starts, ends or changes kind, not each second its clock counts down.
    def penaltyName(r: RobotSnapshot, m: StatusModel) = penalty(r, m.game).map(_.name)
    val robots = after.robots.flatMap { r =>
      val line = Some(robotLine(r, after.links.get(r.robotId), after.game, after.servoLimits))
      def mark(s: RobotSnapshot, m: StatusModel) = RobotRow.servoMark(s, m.servoLimits)
      old.get(r.robotId) match {
        case Some(o) if penaltyName(o, before) != penaltyName(r, after) => line
        case Some(o) if mark(o, before) != mark(r, after)               => line
        case Some(o) if o.signing != r.signing && !r.online             => line
        case Some(o) if o.online == r.online && o.posture == r.posture  => None
        case Some(o) if o.online == r.online && !r.online               => None
        case None if !r.online && r.signing != SigningState.Unsigned    => None
        case _                                                          => line
      }
    }
    val game =
      if (after.game.map(g => (g.gameState, situation(g), g.firstHalf)) ==
          before.game.map(g => (g.gameState, situation(g), g.firstHalf))) None
      else after.game.map(g => gameLine(Some(g)))
    // The first figures say nothing new unless the rule is on; after that, only a change of the gate is news.
    val gate = (before.traffic, after.traffic) match {
      case (None, Some(t)) if t.competition => Some(gateLine(after.traffic))
      // A new reason is news (the game running, or a packet that cannot be read); the state in it is the game line's.
      case (Some(b), Some(a))
          if b.gateOpen != a.gateOpen || (a.competition && kind(b.gateReason) != kind(a.gateReason)) =>
        Some(gateLine(after.traffic))
      case _ => None
    }
    // A warning is news when it first appears (not every refresh its figures change).
    def warningHeads(m: StatusModel) = m.gameSource.toVector.flatMap(_.warnings).map(_.takeWhile(_ != ':'))
    val warnings =
      after.gameSource.toVector.flatMap(_.warnings).filterNot(w => warningHeads(before).contains(w.takeWhile(_ != ':')))
        .map(w => s"WARNING: $w")
    robots ++ game ++ gate ++ warnings
  }
}
