package apps.web

import java.util.Base64

import spray.json._

import naogateway.wire.HaViMoRegion
import naogateway.wire.gamecontroller.GameControlData
import naogateway.api.{
  GameSource,
  GatewayEvent,
  GatewayStats,
  LinkQualityChanged,
  LinkStats,
  RobotForgotten,
  RobotOffline,
  RobotOnline,
  RobotRestarted,
  RobotSnapshot,
  RobotStatusUpdated,
  ServoReadings,
  GameStateUpdated,
  TrafficStats
}
import apps.StatusView
import robotmiddleware.ServoLimits

/** One point of a robot's plots: seconds since the view started, battery (V), round-trip time (ms), loss (0 to 1). */
final case class RobotSample(t: Double, battery: Option[Double], rttMillis: Option[Double], loss: Option[Double])

/** One point of the traffic plot: seconds since the view started, bytes per second out and in, and the budget. */
final case class TrafficSample(t: Double, outBytes: Long, inBytes: Long, budget: Int)

/** One line of the event log: when (seconds since the view started, and wall-clock milliseconds) and what. */
final case class WebEvent(t: Double, wallMillis: Long, kind: String, robotId: Option[Int], text: String)

/** A robot's latest HaViMo2 frame as the page draws it: regions with every push, the grid when it changes. */
final case class VisionView(frame: Long, regions: Vector[HaViMoRegion], grid: Option[Array[Byte]], gridFrame: Long)

/** What the web view shows, owned by the [[WebView]] actor alone. Pure: each change is a function to a new model, and
  * rendering to JSON is total (a value it cannot show becomes null), so the view never dies on a packet it did not
  * expect. Every collection is bounded: plots by `historyPoints`, the log by `maxEvents`, vision by the robots known.
  */
final case class WebModel(
    historyPoints: Int,
    maxEvents: Int,
    robots: Vector[RobotSnapshot] = Vector.empty,
    links: Map[Int, LinkStats] = Map.empty,
    signing: Map[Int, String] = Map.empty,
    traffic: Option[TrafficStats] = None,
    game: Option[GameControlData] = None,
    gameSource: Option[GameSource] = None,
    gateway: Option[GatewayStats] = None,
    robotHistory: Map[Int, Vector[RobotSample]] = Map.empty,
    trafficHistory: Vector[TrafficSample] = Vector.empty,
    events: Vector[WebEvent] = Vector.empty,
    vision: Map[Int, VisionView] = Map.empty,
    eventCount: Long = 0L,
    sampleCount: Long = 0L,
    servoLimits: ServoLimits = ServoLimits()
) {

  /** The model with `event` at the head of the log (newest first), the oldest dropped past `maxEvents`. */
  def logged(event: WebEvent): WebModel = copy(events = (event +: events).take(maxEvents), eventCount = eventCount + 1)

  /** The model after the gateway answered `GetRobots`; robots it no longer lists lose their figures and frames. */
  def withRobots(now: Vector[RobotSnapshot]): WebModel = {
    val ids = now.iterator.map(_.robotId).toSet
    copy(robots = now.sortBy(_.robotId), robotHistory = robotHistory.filter(e => ids(e._1)),
      vision = vision.filter(e => ids(e._1)),
      links = links.filter(e => ids(e._1)))
  }

  /** The model after new link figures; a refusal counter that grew is logged, by kind. */
  def withLinks(now: Vector[LinkStats], t: Double, wall: Long): WebModel = {
    val refusals = now.flatMap { l =>
      val before = links.get(l.robotId).map(_.rejected).getOrElse(Map.empty[String, Long])
      l.rejected.toVector.sortBy(_._1).collect {
        case (kind, n) if n > before.getOrElse(kind, 0L) && links.contains(l.robotId) =>
          WebEvent(t, wall, "refusal", Some(l.robotId),
            s"robot ${l.robotId}: ${n - before.getOrElse(kind, 0L)} refused ($kind, $n in all)")
      }
    }
    refusals.foldLeft(copy(links = now.iterator.map(l => l.robotId -> l).toMap))(_ logged _)
  }

  /** The model after new traffic figures; a change of the competition gate is logged. */
  def withTraffic(now: TrafficStats, t: Double, wall: Long): WebModel = {
    val next = copy(traffic = Some(now))
    traffic match {
      case Some(before) if before.gateOpen != now.gateOpen =>
        next.logged(WebEvent(t, wall, "gate", None, StatusView.gateLine(Some(now))))
      case None if !now.gateOpen => next.logged(WebEvent(t, wall, "gate", None, StatusView.gateLine(Some(now))))
      case _                     => next
    }
  }

  /** The model after the gateway's own figures; datagrams it refused are logged by kind as their counters grow. */
  def withGatewayStats(now: GatewayStats, t: Double, wall: Long): WebModel = {
    val before = gateway.map(_.rejected)
    val refusals = before.toVector.flatMap { b =>
      now.rejected.toVector.sortBy(_._1).collect {
        case (kind, n) if n > b.getOrElse(kind, 0L) =>
          WebEvent(t, wall, "refusal", None, s"gateway: ${n - b.getOrElse(kind, 0L)} refused ($kind, $n in all)")
      }
    }
    refusals.foldLeft(copy(gateway = Some(now)))(_ logged _)
  }

  /** The model after a GameController packet (asked or pushed); a change of state or half is logged. */
  def withGame(now: Option[GameControlData], t: Double, wall: Long): WebModel = {
    def key(g: Option[GameControlData]) = g.map(d => (d.gameState, StatusView.situation(d), d.firstHalf))
    val next = copy(game = now.orElse(game))
    if (now.isDefined && key(now) != key(game)) next.logged(WebEvent(t, wall, "game", None, StatusView.gameLine(now)))
    else next
  }

  /** The model after a gateway event: robots online, offline, restarted, forgotten, link quality, game packets. */
  def withEvent(event: GatewayEvent, t: Double, wall: Long): WebModel = event match {
    case RobotOnline(id, address) => logged(WebEvent(t, wall, "online", Some(id),
          s"robot $id online at ${address.getAddress.getHostAddress}:${address.getPort}"))
    case RobotOffline(id, reason) => logged(WebEvent(t, wall, "offline", Some(id), s"robot $id offline: $reason"))
    case RobotRestarted(id, boot, resynced) =>
      logged(WebEvent(
          t,
          wall,
          "restart",
          Some(id),
          s"robot $id restarted" + boot.fold("")(b => s" (boot $b)") +
            (if (resynced.isEmpty) "" else resynced.mkString(", re-synced ", ", ", ""))
        ))
    case RobotForgotten(id, reason) => logged(WebEvent(t, wall, "offline", Some(id), s"robot $id forgotten: $reason"))
    case LinkQualityChanged(id, q)  => logged(WebEvent(t, wall, "quality", Some(id), s"robot $id link ${q.name}"))
    case GameStateUpdated(data)     => withGame(Some(data), t, wall)
    case RobotStatusUpdated(snapshot) =>
      copy(robots = robots.map(r => if (r.robotId == snapshot.robotId) snapshot else r))
  }

  /** The model after a HaViMo2 frame of a robot it lists (frames of others are dropped: nothing unbounded is kept). */
  def withRegions(robotId: Int, frame: Long, regions: Vector[HaViMoRegion]): WebModel =
    if (!robots.exists(_.robotId == robotId)) this
    else {
      val old = vision.get(robotId)
      copy(vision = vision.updated(robotId,
        VisionView(frame, regions.take(naogateway.wire.HaViMo.MaxRegions), old.flatMap(_.grid),
          old.fold(0L)(_.gridFrame))))
    }

  /** The model after a HaViMo2 grid frame of a robot it lists. */
  def withGrid(robotId: Int, frame: Long, cells: Array[Byte]): WebModel =
    if (!robots.exists(_.robotId == robotId)) this
    else {
      val old = vision.getOrElse(robotId, VisionView(frame, Vector.empty, None, 0L))
      copy(vision = vision.updated(robotId, old.copy(grid = Some(cells), gridFrame = frame)))
    }

  /** The model with one more point on every plot, taken from the current figures. */
  def sampled(t: Double): WebModel = {
    val perRobot = robots.map { r =>
      val row = apps.RobotRow.of(r, links.get(r.robotId))
      val point = RobotSample(t, row.battery, row.rttMillis, row.loss)
      r.robotId -> (robotHistory.getOrElse(r.robotId, Vector.empty) :+ point).takeRight(historyPoints)
    }.toMap
    val trafficPoint =
      traffic.map(s => TrafficSample(t, s.outBytesLastSecond, s.inBytesLastSecond, s.budgetBytesPerSecond))
    copy(robotHistory = perRobot, trafficHistory = (trafficHistory ++ trafficPoint).takeRight(historyPoints),
      sampleCount = sampleCount + 1)
  }
}

/** The JSON the page reads (docs/web.md, "What the page receives"). */
object WebJson {

  private def num(d: Double): JsValue = if (d.isNaN || d.isInfinite) JsNull else JsNumber(d)
  private def opt[A](a: Option[A])(f: A => JsValue): JsValue = a.fold[JsValue](JsNull)(f)
  // A string a robot or a peer wrote, with its control characters replaced before it reaches the page.
  private def text(s: String): JsValue = JsString(naogateway.api.Printable.text(s))

  /** One robot's card (its [[apps.RobotRow]]): what it reports, its link and clock, signing and refusals by kind, the
    * GameController's penalty when `game` has taken it off the game (the status screen's rule, StatusView.penalty), and
    * its servo table, each servo marked hot or low on voltage by `limits`.
    */
  def robot(r: RobotSnapshot, link: Option[LinkStats], signing: Option[String],
      game: Option[GameControlData] = None, limits: ServoLimits = ServoLimits()): JsObject = {
    val row = apps.RobotRow.of(r, link)
    JsObject(
      "id" -> JsNumber(row.robotId),
      "online" -> JsBoolean(row.online),
      "quality" -> opt(row.quality)(q => JsString(q.name)),
      "address" -> opt(row.address)(JsString(_)),
      "battery" -> opt(row.battery)(num),
      "posture" -> opt(row.posture)(p => JsString(p.name)),
      "role" -> opt(row.report.role)(text),
      "agent" -> opt(row.report.agent)(text),
      "team" -> opt(row.report.teamId)(JsNumber(_)),
      "uptimeMs" -> opt(row.report.uptimeMillis)(JsNumber(_)),
      "rttMs" -> opt(row.rttMillis)(num),
      "loss" -> opt(row.loss)(num),
      "clock" -> opt(row.clock) { c =>
        JsObject(
          "driftPpm" -> num(c.driftPpm),
          "driftBoundPpm" -> num(c.driftBoundPpm),
          "driftSettled" -> JsBoolean(c.driftSettled),
          "errorBoundMs" -> num(c.errorBoundMillis),
          "samples" -> JsNumber(c.samples)
        )
      },
      "signing" -> opt(signing)(JsString(_)),
      "development" -> JsBoolean(row.report.development),
      "penalty" -> opt(StatusView.penalty(r, game)) { p =>
        JsObject("name" -> JsString(p.name), "secondsLeft" -> JsNumber(p.secsTillUnpenalised))
      },
      "refused" -> JsObject(row.refused.map { case (k, v) => k -> JsNumber(v) }),
      "servos" -> opt(r.servos)(servos(_, limits))
    )
  }

  /** A robot's servo table (docs/protocol.md 6.8): per servo its id, raw position and degrees from centre, load,
    * voltage (V), temperature (°C), error byte, and whether it is silent, hot or low on voltage.
    */
  def servos(t: ServoReadings, limits: ServoLimits): JsObject = JsObject(
    "busErrors" -> opt(t.busErrors)(JsNumber(_)),
    "list" -> JsArray(t.servos.map { s =>
      JsObject(
        "id" -> JsNumber(s.id),
        "position" -> opt(s.position)(JsNumber(_)),
        "degrees" -> opt(s.degrees)(num),
        "load" -> opt(s.load)(JsNumber(_)),
        "voltage" -> opt(s.voltage)(num),
        "temperature" -> opt(s.temperature)(JsNumber(_)),
        "error" -> JsNumber(s.error),
        "silent" -> JsBoolean(s.silent),
        "hot" -> JsBoolean(limits.hot(s)),
        "lowVoltage" -> JsBoolean(limits.lowVoltage(s))
      )
    })
  )

  /** The game: GameController version and source, state, time, score, gate and traffic. */
  def game(m: WebModel): JsObject = JsObject(
    "version" -> opt(m.game)(g => JsNumber(g.version.number)),
    "source" -> opt(m.gameSource)(s => text(s.describe)),
    "state" -> opt(m.game)(g => JsString(StatusView.stateName(g.gameState))),
    "secondary" -> opt(m.game)(g => JsString(StatusView.situation(g).mkString(", "))),
    "firstHalf" -> opt(m.game)(g => JsBoolean(g.firstHalf)),
    "secsRemaining" -> opt(m.game)(g => JsNumber(g.secsRemaining)),
    "secondaryTime" -> opt(m.game.flatMap(_.secondaryClock))(JsNumber(_)),
    "teams" -> opt(m.game)(g =>
      JsArray(Vector(g.team0, g.team1).map(t =>
          JsObject("team" -> JsNumber(t.teamNumber), "score" -> JsNumber(t.score))))),
    "line" -> JsString(StatusView.gameLine(m.game)),
    "gate" -> opt(m.traffic)(t =>
      JsString(if (!t.competition) "open (competition rule off)" else if (t.gateOpen) "open" else "closed")),
    "traffic" -> opt(m.traffic) { t =>
      JsObject(
        "outBytes" -> JsNumber(t.outBytesLastSecond),
        "inBytes" -> JsNumber(t.inBytesLastSecond),
        "budget" -> JsNumber(t.budgetBytesPerSecond),
        "refusedByRule" -> JsNumber(t.refusedByRule),
        "dropped" -> JsNumber(t.dropped)
      )
    },
    "refused" -> JsObject(m.gateway.fold(Map.empty[String, Long])(_.rejected).map { case (k, v) => k -> JsNumber(v) })
  )

  /** A region as FU-Remote draws it: colour class, bounding box, centre of mass, pixels. */
  def region(r: HaViMoRegion): JsObject = JsObject(
    "colour" -> JsNumber(r.colour),
    "pixels" -> JsNumber(r.pixels),
    "minX" -> JsNumber(r.minX),
    "maxX" -> JsNumber(r.maxX),
    "minY" -> JsNumber(r.minY),
    "maxY" -> JsNumber(r.maxY),
    "cx" -> num(r.centreX),
    "cy" -> num(r.centreY)
  )

  /** A robot's frame; the grid's 768 cells (base64) only when `withGrid`. */
  def vision(v: VisionView, withGrid: Boolean): JsObject = {
    val base = Map[String, JsValue]("frame" -> JsNumber(v.frame), "regions" -> JsArray(v.regions.map(region)))
    JsObject(if (withGrid) base ++ v.grid.map(g => "grid" -> JsString(Base64.getEncoder.encodeToString(g))) else base)
  }

  /** A log line. */
  def event(e: WebEvent): JsObject =
    JsObject("t" -> num(e.t), "wall" -> JsNumber(e.wallMillis), "kind" -> text(e.kind),
      "robot" -> opt(e.robotId)(JsNumber(_)), "text" -> text(e.text))

  /** A robot's plot point as [t, battery, rtt, loss]. */
  def robotSample(s: RobotSample): JsArray =
    JsArray(num(s.t), opt(s.battery)(num), opt(s.rttMillis)(num), opt(s.loss)(num))

  /** A traffic plot point as [t, out, in, budget]. */
  def trafficSample(s: TrafficSample): JsArray =
    JsArray(num(s.t), JsNumber(s.outBytes), JsNumber(s.inBytes), JsNumber(s.budget))

  /** A push: the current figures, the frames, the newest `newEvents` log lines, and the plots' points taken since the
    * last push (`samples`). `grids` names the robots whose grid goes along. The first message of a connection is a push
    * with `hello` set, every plot point and the whole log.
    */
  def push(m: WebModel, t: Double, newEvents: Int, samples: Int, grids: Set[Int], hello: Boolean): String = JsObject(
    "type" -> JsString(if (hello) "hello" else "push"),
    "t" -> num(t),
    "historyPoints" -> JsNumber(m.historyPoints),
    "robots" -> JsArray(
      m.robots.map(r => robot(r, m.links.get(r.robotId), m.signing.get(r.robotId), m.game, m.servoLimits))),
    "game" -> game(m),
    "vision" -> JsObject(m.vision.map { case (id, v) => id.toString -> vision(v, grids(id)) }),
    "events" -> JsArray(m.events.take(newEvents).map(event)),
    "samples" -> JsObject(
      "robots" -> JsObject(m.robotHistory.map { case (id, h) =>
        id.toString -> JsArray(h.takeRight(samples).map(robotSample))
      }),
      "traffic" -> JsArray(m.trafficHistory.takeRight(samples).map(trafficSample))
    )
  ).compactPrint
}
