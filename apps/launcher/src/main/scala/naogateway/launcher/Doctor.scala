package naogateway.launcher

import java.net.InetSocketAddress
import java.nio.file.{Files, Path}

import scala.concurrent.duration._
import scala.concurrent.{ExecutionContext, Future}
import scala.util.control.NonFatal

import akka.actor.typed.scaladsl.AskPattern._
import akka.actor.typed.{ActorRef, ActorSystem}
import akka.util.Timeout
import com.typesafe.config.Config

import naogateway.gateway.recording.Retention
import naogateway.wire.gamecontroller.{GameControlData, GameControlVersion}
import naogateway.access.GatewayAccess
import naogateway.api.{GameSource, GatewayStats, LinkStats, RobotLinks, RobotSnapshot, TrafficStats}
import naogateway.gateway.{GatewaySettings, Rejection}
import apps.control.Finding

/** `robotctl doctor`: what a team checks first when something does not work, each problem with its fix. The checks are
  * pure functions over facts gathered from the running gateway ([[gather]]) and the machine, so each can be provoked in
  * a test; the control port answers `doctor` with their lines (docs/robotctl.md).
  */
object Doctor {

  private def ok(check: String, text: String) = Finding(check, text, problem = false)
  private def fail(check: String, text: String, fix: String) = Finding(check, text, problem = true, fix)

  /** What the gateway knows of the GameController: the latest packet, where game state comes from, the packets it
    * refused by kind, and whether the competition gate applies. Read through [[gameSnapshot]], the one place that asks
    * the gateway, so more GameController facts (versions, the fail-safe gate, the team message budget) join here.
    */
  final case class GameSnapshot(latest: Option[GameControlData], source: GameSource, refused: Map[String, Long],
      competition: Boolean,
      gateReason: Option[String] = None)

  /** The disk of the recording directory: whether the gateway can write there, and the space left. */
  final case class Disk(directory: Path, writable: Boolean, usableBytes: Long)

  /** Everything the checks look at. */
  final case class Facts(
      settings: GatewaySettings,
      robots: Vector[RobotSnapshot],
      links: Vector[LinkStats],
      stats: GatewayStats,
      traffic: Option[TrafficStats],
      game: GameSnapshot,
      unknownKeys: Vector[String],
      disk: Option[Disk],
      fuRemoteListening: Option[Boolean]
  )

  /** A clock estimate whose error bound stays above this has not converged (docs/architecture.md §6.1). */
  val ClockBoundMillis: Double = 50.0

  /** Keep-alives (10 s of them) before an estimate is judged: with fewer the bound is wide by design. */
  val ClockJudgedAfter: Int = 50

  /** A recording disk with less free space than this is a problem before the week is out. */
  val MinFreeBytes: Long = 2L * 1024 * 1024 * 1024

  /** Share of the team budget at which the traffic check warns. */
  val BudgetWarnShare: Double = 0.8

  private val SignatureRejections: Set[String] =
    Set(Rejection.Unsigned, Rejection.SignatureNotLast, Rejection.MalformedSignature, Rejection.BadSignature,
      Rejection.Replayed).map(_.name)

  /** Every check over `facts`, in the order robotctl prints them. */
  def findings(facts: Facts): Vector[Finding] =
    gameControllerFindings(facts.game) ++ robotFindings(facts) ++ signingFindings(facts) ++ clockFindings(
      facts.robots) ++
      budgetFindings(facts.traffic) ++ recordingFindings(facts.stats.recording, facts.disk) ++ tapFindings(
        facts.stats.tap) ++ relayFindings(
        facts) ++ configFindings(facts.unknownKeys)

  /** The GameController: heard, from a trusted source, in a version the gateway reads, with the gate following it. */
  def gameControllerFindings(game: GameSnapshot): Vector[Finding] = {
    val unreadable = game.refused.getOrElse(Rejection.BadGameControllerPacket.name, 0L)
    val heard = game.latest match {
      case None =>
        fail(
          "GameController",
          "no packet heard from a trusted source",
          "start the GameController on the field's network (it broadcasts to UDP 3838); this machine must be on " +
            "that subnet " +
            "and listen on naogateway.game-controller.port"
        )
      case Some(p) =>
        ok("GameController", s"heard, version ${p.version.number}, state ${p.gameState}, ${game.source.describe}")
    }
    val trusted =
      if (game.source.untrusted > 0)
        Vector(fail(
            "GameController source",
            s"${game.source.untrusted} packet(s) from addresses not in trusted-sources (${game.source.trusted}) " +
              s"ignored",
            "put the GameController's address or subnet in naogateway.game-controller.trusted-sources " +
              "(NAOGATEWAY_GAMECONTROLLER_TRUSTED)"
          ))
      else Vector.empty
    val versions =
      if (unreadable > 0)
        Vector(fail(
            "GameController version",
            s"$unreadable packet(s) the gateway cannot read (refused as ${Rejection.BadGameControllerPacket.name})",
            s"the gateway reads versions ${GameControlVersion.all.map(_.number).mkString(", ")} (docs/protocol.md " +
              s"§10), and 18 or a later one by its shared header (§10.12); " +
              "a GameController of another version closes the competition gate (fail safe, §10.7) until the gateway " +
              "is updated"
          ))
      else Vector.empty
    // A second GameController on the field, the team's message budget running out, messages over the size limit.
    // A GameController of a version read by its shared header only, contradictions the competition gate counted.
    val warnings = game.source.warnings.map {
      case w if w.startsWith("GameController version") =>
        fail(
          "GameController version",
          w,
          "the gate follows its shared header, the teams and penalties are not shown: update naogateway " +
            "(docs/protocol.md §10.12)"
        )
      case w if w.startsWith("competition gate") =>
        fail(
          "competition gate",
          w,
          "someone on the WiFi may forge the GameController's packets, or a second GameController shares its " +
            "address: the gate stays closed meanwhile (docs/protocol.md §10.7); find the sender"
        )
      case w =>
        fail("GameController", w,
          "see docs/protocol.md §10.8; game state is taken only from naogateway.game-controller.trusted-sources")
    }
    val budget = game.source.budget.toVector.map(b => ok("team messages", b))
    val gate =
      if (!game.competition)
        Vector(ok("competition gate", "off (naogateway.competition.enabled = off): the gateway sends during games"))
      else if (game.latest.isEmpty && game.gateReason.isDefined)
        Vector(fail("competition gate", s"on and closed: ${game.gateReason.get}",
            "see the GameController checks above"))
      else if (game.latest.isEmpty)
        Vector(fail("competition gate", "on, but no game state yet: it opens and closes only with trusted packets",
            "see the GameController check above"))
      else Vector(ok("competition gate",
          s"on, following the GameController (${game.latest.get.gameState})" +
            game.gateReason.fold(", open now")(why => s", closed now: $why")))
    heard +: (trusted ++ versions ++ warnings ++ budget ++ gate)
  }

  /** Robots configured but never heard, offline, heard but not configured, and ids claimed from an unexpected address.
    */
  def robotFindings(facts: Facts): Vector[Finding] = {
    val byId = facts.robots.map(r => r.robotId -> r).toMap
    val configured = facts.settings.robots.flatMap { r =>
      byId.get(r.robotId) match {
        case Some(s) if s.online => None
        case Some(s) if s.receivedAtNanos != 0L =>
          Some(fail(
              s"robot ${r.robotId}",
              s"offline (configured at ${host(r.address)}, heard before)",
              "check its battery and WiFi module; it must keep sending keep-alives every 200 ms (robotctl status " +
                "shows its loss)"
            ))
        case _ =>
          Some(fail(
              s"robot ${r.robotId}",
              s"configured at ${host(r.address)} but never heard",
              s"switch it on; its firmware must send keep-alives to this machine's UDP ${facts.settings.robotPort} " +
                s"from ${host(r.address)} " +
                "(README, \"With real robots\": when a robot does not come online)"
            ))
      }
    }
    val strangers =
      if (facts.settings.robots.isEmpty) Vector.empty
      else facts.robots.filterNot(s => facts.settings.robots.exists(_.robotId == s.robotId)).map { s =>
        fail(
          s"robot ${s.robotId}",
          s"heard from ${host(s.address)} but not configured",
          s"if it is yours, add { id = ${s.robotId}, address = \"${host(s.address)}\" } to naogateway.robots; if " +
            s"not, another team's robot sends here"
        )
      }
    val mismatched = facts.stats.rejected.getOrElse(Rejection.RobotIdMismatch.name, 0L)
    val unexpected =
      if (mismatched > 0) {
        val sources = facts.stats.rejectedBySource.keys.toVector.sorted.take(5).mkString(", ")
        Vector(fail(
            "robot addresses",
            s"$mismatched frame(s) whose robot id belongs to another address (sources: $sources)",
            "a robot's IP address changed, or two robots share an id: give each robot its static address and fix " +
              "naogateway.robots"
          ))
      } else Vector.empty
    val online = facts.robots.count(_.online)
    val summary =
      ok("robots", s"$online of ${facts.robots.size} known robot(s) online, ${facts.settings.robots.size} configured")
    summary +: (configured ++ strangers ++ unexpected)
  }

  /** Which robots sign; robots whose frames fail verification; in competition mode, robots that do not sign (no team
    * key, `signing = off`) and robots running a development build (`RobotHealth.development`, docs/protocol.md 6.7).
    */
  def signingFindings(facts: Facts): Vector[Finding] = {
    val settings = facts.settings
    val competition = settings.competition
    val signing = settings.robots.filter(_.signing == naogateway.gateway.RobotSigning.Required).map(_.robotId)
    val off = settings.robots.filter(_.signing == naogateway.gateway.RobotSigning.Off).map(_.robotId)
    val summary =
      if (settings.signingKey.isEmpty)
        if (competition)
          fail(
            "signing",
            "competition mode without a team key: no robot's frames are signed",
            "set naogateway.signing.key (env NAOGATEWAY_SIGNING_KEY) and build each robot with its key " +
              "(robotctl keys <id>; docs/protocol.md 6.7)"
          )
        else ok("signing", "off: no team key (naogateway.signing.key)")
      else if (signing.nonEmpty)
        ok("signing",
          s"robot(s) ${signing.mkString(", ")} sign their frames with their robot keys; " +
            "robots not configured must sign too")
      else ok("signing", "a team key is set; robots not configured must sign")
    val offInCompetition = off.filter(_ => competition && settings.signingKey.isDefined).map { id =>
      fail(
        s"robot $id signing",
        "signing = off in competition mode: anyone on the WiFi can command this robot",
        s"build the robot with its key (robotctl keys $id) and remove signing = off from its entry in naogateway.robots"
      )
    }
    val development = facts.robots.filter(_.development).map { r =>
      val text = "runs a development build: it neither signs nor checks signatures (RobotHealth.development)"
      if (competition)
        fail(s"robot ${r.robotId} firmware", text,
          s"flash a field build with the robot's key (robotctl keys ${r.robotId}; docs/firmware.md)")
      else ok(s"robot ${r.robotId} firmware", text)
    }
    val failures = facts.links.flatMap { l =>
      val failed = l.rejected.filter { case (k, _) => SignatureRejections(k) }
      Option.when(failed.values.sum > 0)(fail(
          s"robot ${l.robotId} signing",
          s"${failed.values.sum} frame(s) failed verification " +
            s"(${failed.toVector.sorted.map { case (k, n) => s"$k $n" }.mkString(", ")})",
          s"the robot's firmware must sign with its robot key (robotctl keys ${l.robotId}, from the team key " +
            "naogateway.signing.key; docs/protocol.md 6.7); a firmware that does not sign yet needs signing = off " +
            "for this robot"
        ))
    }
    (summary +: offInCompetition) ++ development ++ failures
  }

  /** Online robots whose clock estimate has not converged. */
  def clockFindings(robots: Vector[RobotSnapshot]): Vector[Finding] =
    robots.filter(_.online).flatMap { r =>
      r.clock.filter(c => c.samples >= ClockJudgedAfter && c.errorBoundMillis > ClockBoundMillis).map { c =>
        fail(
          s"robot ${r.robotId} clock",
          f"estimate does not converge (error bound ±${c.errorBoundMillis}%.0f ms over ${c.samples} keep-alives)",
          "its keep-alives arrive irregularly (WiFi load, loss: robotctl status) or its clock jumps; the firmware " +
            "must stamp each " +
            "keep-alive with its uptime in ms (docs/protocol.md 6.2)"
        )
      }
    }

  /** The team's traffic against the budget. */
  def budgetFindings(traffic: Option[TrafficStats]): Vector[Finding] = traffic.toVector.map { t =>
    val share = t.outBytesLastSecond.toDouble / t.budgetBytesPerSecond
    if (t.dropped > 0 || share >= BudgetWarnShare)
      fail(
        "team budget",
        f"${t.outBytesLastSecond} B/s of ${t.budgetBytesPerSecond} B/s (${share * 100}%.0f %%), ${t.dropped} " +
          f"datagram(s) dropped",
        "the gateway sends too much: fewer debug options enabled, fewer apps walking robots, or a lower camera rate " +
          "(docs/architecture.md, the traffic budget)"
      )
    else ok("team budget", f"${t.outBytesLastSecond} B/s of ${t.budgetBytesPerSecond} B/s (${share * 100}%.0f %%)")
  }

  /** The recording directory: writable, with room, and the recorder not failing. */
  def recordingFindings(r: naogateway.api.recording.RecordingStats, disk: Option[Disk]): Vector[Finding] =
    disk.toVector.flatMap { d =>
      val place =
        if (!d.writable) Vector(fail("recording", s"${d.directory} is not writable",
            "make it writable, or set naogateway.recording.directory (NAOGATEWAY_RECORDING_DIR)"))
        else if (d.usableBytes < MinFreeBytes)
          Vector(fail(
              "recording",
              s"${Retention.bytesText(d.usableBytes)} free on the disk of ${d.directory}",
              "free disk space, or lower naogateway.recording.retention.max-total-bytes so old recordings are deleted"
            ))
        else Vector(ok("recording",
            s"${d.directory} writable, ${Retention.bytesText(d.usableBytes)} free" + r.retention.fold("")(k =>
              s"; ${k.describe}")))
      val failing =
        if (r.failed > 0) Vector(fail("recording writes", s"${r.failed} entries could not be written",
            s"check the disk of ${d.directory} (full? removed?)"))
        else Vector.empty
      place ++ failing
    }

  /** The tap's readers (the recorder, the FU-Remote relay, the live feed): one that fell behind lost what did not fit
    * its queue. The robots lose nothing by it (the gateway never waits for a reader), but the recording or FU-Remote
    * then lacks datagrams, which a team finds out only afterwards.
    */
  def tapFindings(readers: Vector[naogateway.api.recording.TapReaderStats]): Vector[Finding] =
    readers.filter(_.dropped > 0).map { r =>
      val fix = r.reader match {
        case "recorder" =>
          "raise naogateway.recording.queue-capacity, record to a faster disk, or give the gateway's machine more room"
        case "fu-remote-relay" => "give the gateway's machine more room (FU-Remote's own datagrams are not lost)"
        case _                 => "close clients that cannot keep up, or give the gateway's machine more room"
      }
      fail("tap", s"${r.reader} fell behind and lost ${r.dropped} of ${r.delivered + r.dropped} entries", fix)
    }

  /** FU-Remote behind the relay: something must listen where the relay sends. */
  def relayFindings(facts: Facts): Vector[Finding] = (facts.settings.relay, facts.fuRemoteListening) match {
    case (Some(to), Some(false)) =>
      Vector(fail(
          "FU-Remote relay",
          s"nothing listens on UDP ${host(to)}:${to.getPort}, where robot traffic is relayed",
          s"start FU-Remote on port ${to.getPort} (it cannot have 11011, which the gateway holds), or turn " +
            s"naogateway.fu-remote-relay off"
        ))
    case (Some(to), _) => Vector(ok("FU-Remote relay", s"relaying to ${host(to)}:${to.getPort}"))
    case (None, _)     => Vector.empty
  }

  /** Config keys that no reference knows. */
  def configFindings(unknownKeys: Vector[String]): Vector[Finding] =
    if (unknownKeys.isEmpty) Vector(ok("config", "every key set is a known setting"))
    else unknownKeys.map(k =>
      fail("config", s"$k is not a setting and is ignored",
        "correct the typo (every key with its default is in the reference.conf files)"))

  /** The cluster's transport ([[robotmiddleware.cluster.ClusterTls]]): plain TCP on loopback, or TLS with the team's
    * certificate; a node that would be refused is a problem.
    */
  def clusterFinding(c: Config): Finding =
    robotmiddleware.cluster.ClusterTls.describe(c) match {
      case Right(how) => ok("cluster", how)
      case Left(line) =>
        fail("cluster", line,
          "give the node the team's key store and trust store (docs/cluster.md), or keep it on loopback")
    }

  private def host(a: InetSocketAddress): String = Option(a.getAddress).fold(a.getHostString)(_.getHostAddress)

  // ------------------------------------------------------------------------------------------------- gathering

  /** The gateway's game snapshot for the GameController checks. */
  def gameSnapshot(gateway: ActorRef[GatewayAccess.Query], competition: Boolean)(implicit system: ActorSystem[_],
      timeout: Timeout): Future[GameSnapshot] = {
    implicit val ec: ExecutionContext = system.executionContext
    for {
      latest <- gateway.ask[Option[GameControlData]](GatewayAccess.GetGameState(_))
      source <- gateway.ask[GameSource](GatewayAccess.GetGameSource(_))
      stats <- gateway.ask[GatewayStats](GatewayAccess.GetStats(_))
    } yield GameSnapshot(latest, source, stats.rejected, competition)
  }

  /** Where the recording directory is, whether it can be written (creating it if needed), and its free space. */
  def disk(directory: Path): Disk = {
    val existing = Iterator.iterate(directory.toAbsolutePath)(_.getParent).takeWhile(_ != null).find(Files.exists(_))
    val writable = existing.exists(p => Files.isDirectory(p) && Files.isWritable(p))
    val usable = existing.map(p =>
      try Files.getFileStore(p).getUsableSpace
      catch { case NonFatal(_) => 0L }).getOrElse(0L)
    Disk(directory, writable, usable)
  }

  /** Whether a program listens on UDP `to` (on this machine): binding it fails when one does. None when not local. */
  def listening(to: InetSocketAddress): Option[Boolean] =
    Option(to.getAddress).filter(a => a.isLoopbackAddress || a.isAnyLocalAddress).map { _ =>
      Preflight.probe(Preflight.PortUse(Preflight.Transport.Udp(reuse = false), host(to), to.getPort, "",
          "")) == Preflight.Probe.InUse
    }

  /** Asks the gateway and looks at the machine; the facts for [[findings]]. */
  def gather(gateway: ActorRef[GatewayAccess.Query], config: Config)(implicit system: ActorSystem[_]): Future[Facts] = {
    implicit val ec: ExecutionContext = system.executionContext
    implicit val timeout: Timeout = 3.seconds
    val settings = GatewaySettings.fromConfig(config.getConfig("naogateway"))
    for {
      robots <- gateway.ask[Vector[RobotSnapshot]](GatewayAccess.GetRobots(_))
      links <- gateway.ask[RobotLinks](GatewayAccess.GetLinkStats(_))
      stats <- gateway.ask[GatewayStats](GatewayAccess.GetStats(_))
      traffic <-
        gateway.ask[TrafficStats](GatewayAccess.GetTraffic(_)).map(Some(_)).recover { case NonFatal(_) =>
          None
        }
      game <- gameSnapshot(gateway, settings.competition).map(_.copy(gateReason = traffic.flatMap(_.gateReason)))
      machine <- Future {
        (Preflight.unknownKeys(config, Preflight.knownKeys),
          Option.when(settings.recording.enabled)(disk(settings.recording.directory)),
          settings.relay.flatMap(listening))
      }(ExecutionContext.global)
    } yield Facts(settings, robots, links.links, stats, traffic, game, machine._1, machine._2, machine._3)
  }
}
