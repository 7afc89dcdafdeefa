package naogateway.gateway

import java.net.InetSocketAddress

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.jdk.DurationConverters._

import akka.actor.typed.ActorSystem
import com.typesafe.config.Config

import naogateway.gateway.recording.RecordingSettings
import naogateway.wire.SigningKey
import naogateway.wire.stream.StreamSettings
import naogateway.access.RestartBackoff
import naogateway.gateway.gamecontroller.{MonitorRole, MonitorSettings, TeamMessageSettings}
import naogateway.gateway.robot.ClockSyncSettings

/** A robot known from configuration: its id, where it receives (its IP, which identifies it, at its receive port), and
  * whether its frames must be signed.
  */
final case class StaticRobot(robotId: Int, address: InetSocketAddress, signing: RobotSigning = RobotSigning.Off)

/** Liveness settings of the heartbeat. */
final case class HeartbeatSettings(
    keepAliveInterval: FiniteDuration,
    quietAfter: FiniteDuration,
    probeTimeout: FiniteDuration,
    chances: Int,
    qualityWindow: FiniteDuration,
    degradedBelow: Double,
    goodAbove: Double,
    probeBackoffMax: FiniteDuration = 30.seconds,
    readerGrace: FiniteDuration = 1.second
) {
  require(keepAliveInterval > Duration.Zero, "heartbeat.keep-alive-interval must be positive")
  require(quietAfter >= keepAliveInterval, "heartbeat.quiet-after must be at least one keep-alive interval")
  require(probeTimeout > Duration.Zero, "heartbeat.probe-timeout must be positive")
  require(chances >= 1, "heartbeat.chances must be at least 1")
  require(qualityWindow >= keepAliveInterval * 2, "heartbeat.quality-window must cover at least two keep-alives")
  require(0 < degradedBelow && degradedBelow <= goodAbove && goodAbove <= 1,
    "need 0 < degraded-below <= good-above <= 1")
  require(readerGrace >= Duration.Zero && readerGrace <= 10.seconds, "heartbeat.reader-grace must be 0 to 10 s")
  require(probeBackoffMax >= probeTimeout * chances.toLong,
    "heartbeat.probe-backoff-max must be at least chances x probe-timeout")

  /** How long one round of probes lasts when none is answered: the first pause of the back-off. */
  def probeRound: FiniteDuration = probeTimeout * chances.toLong

  /** The pause after `silentRounds` rounds in a row without an answer: doubling from one round, at most the maximum. */
  def probeBackoff(silentRounds: Int): FiniteDuration =
    if (silentRounds <= 0) Duration.Zero
    else {
      val doublings = math.min(silentRounds - 1, 30)
      val nanos =
        math.min(probeRound.toNanos.toDouble * math.pow(2, doublings.toDouble), probeBackoffMax.toNanos.toDouble)
      nanos.toLong.nanos
    }

  /** Worst-case time from the last keep-alive to offline. */
  def detection: FiniteDuration = quietAfter + probeTimeout * chances.toLong
}

/** Call settings: timeout, retries of idempotent calls, and the bound of waiting commands. */
final case class CallSettings(timeout: FiniteDuration, idempotentRetries: Int, stashCapacity: Int) {
  require(timeout > Duration.Zero, "calls.timeout must be positive")
  require(idempotentRetries >= 0, "calls.idempotent-retries must not be negative")
  require(stashCapacity >= 1, "calls.stash-capacity must be at least 1")
}

/** The team's traffic budget, and the datagrams each priority class may queue behind it. */
final case class BudgetSettings(teamBytesPerSecond: Int, robotBytesPerSecond: Int, warnAt: Double,
    probeShare: Double = 0.1,
    queueCapacity: Int = 1024) {
  require(teamBytesPerSecond >= 1400, "budget.team-bytes-per-second must allow at least one datagram")
  require(robotBytesPerSecond == 0 || robotBytesPerSecond >= 1400,
    "budget.robot-bytes-per-second is 0 (none) or >= 1400")
  require(warnAt > 0 && warnAt <= 1, "budget.warn-at must be in (0, 1]")
  require(probeShare > 0 && probeShare <= 1, "budget.probe-share must be in (0, 1]")
  require(probeBytesPerSecond >= 100, "budget.probe-share of the team budget must allow at least 100 bytes per second")
  require(queueCapacity >= 1 && queueCapacity <= 1000000, "budget.queue-capacity must be between 1 and 1000000")

  /** The most bytes heartbeat probes may take in any 1 s window. */
  def probeBytesPerSecond: Long = (teamBytesPerSecond * probeShare).toLong
}

/** Robots the network introduces (`naogateway.discovery`): whether keep-alives create robots, how many discovered
  * robots may be known at once, and when a discovered robot that is not online is forgotten.
  */
final case class DiscoverySettings(
    enabled: Boolean,
    maxRobots: Int,
    forgetUnreachedAfter: FiniteDuration,
    forgetOfflineAfter: FiniteDuration
) {
  require(maxRobots >= 0 && maxRobots <= 1000, "discovery.max-robots must be between 0 and 1000")
  require(forgetUnreachedAfter >= 1.second, "discovery.forget-unreached-after must be at least 1 s")
  require(forgetOfflineAfter >= 1.second, "discovery.forget-offline-after must be at least 1 s")
}

/** The defaults, for settings built in code. */
object DiscoverySettings {
  val default: DiscoverySettings = DiscoverySettings(enabled = true, maxRobots = 16, 10.seconds, 2.minutes)
}

/** A robot that serves the RPC over a ZeroMQ REP socket at `endpoint`, e.g. `tcp://127.0.0.1:5600`. */
final case class ZeroMqRobot(robotId: Int, endpoint: String) {
  require(robotId >= 0, s"zeromq.robots: robot id $robotId must not be negative")

  /** The endpoint's host and port, for snapshots and events. */
  val address: InetSocketAddress = endpoint match {
    case ZeroMqRobot.TcpEndpoint(host, port) if port.toInt > 0 && port.toInt <= 65535 =>
      new InetSocketAddress(host, port.toInt)
    case _ =>
      throw new IllegalArgumentException(s"zeromq.robots: robot $robotId: '$endpoint' is not tcp://<host>:<port>")
  }
}

/** Reading endpoints. */
object ZeroMqRobot {
  private val TcpEndpoint = "tcp://([^:/]+):([0-9]{1,5})".r
}

/** The links to ZeroMQ robots: which robots, how often their status is polled, and their own liveness timing. */
final case class ZeroMqLinkSettings(
    robots: Vector[ZeroMqRobot],
    statusInterval: FiniteDuration,
    statusTimeout: FiniteDuration,
    sendQueue: Int,
    pollTimeout: FiniteDuration,
    handshakeTimeout: FiniteDuration,
    heartbeat: HeartbeatSettings
) {
  require(statusInterval > Duration.Zero, "zeromq.status-interval must be positive")
  require(statusTimeout > statusInterval, "zeromq.status-timeout must be longer than zeromq.status-interval")
  require(sendQueue >= 1, "zeromq.send-queue must be at least 1")
  require(handshakeTimeout >= 10.millis, "zeromq.handshake-timeout must be at least 10 ms")
  require(pollTimeout >= 1.milli && pollTimeout <= 1.second, "zeromq.poll-timeout must be between 1 ms and 1 s")
  require(robots.map(_.robotId).distinct.size == robots.size, "zeromq.robots: every robot id may appear only once")
}

/** The restart back-offs of the gateway's supervised actors (`naogateway.supervision`). */
final case class SupervisionSettings(
    outbox: RestartBackoff = RestartBackoff(100.millis, 5.seconds, 0.2),
    robot: RestartBackoff = RestartBackoff(200.millis, 10.seconds, 0.2),
    robotChildren: RestartBackoff = RestartBackoff(200.millis, 5.seconds, 0.2)
)

/** Everything the gateway reads from `naogateway { ... }`. */
final case class GatewaySettings(
    bindAddress: String,
    robotPort: Int,
    robotReceivePort: Int,
    gameControllerEnabled: Boolean,
    gameControllerBindAddress: String,
    gameControllerPort: Int,
    gameControllerReuseAddress: Boolean,
    relay: Option[InetSocketAddress],
    robots: Vector[StaticRobot],
    discovery: DiscoverySettings,
    heartbeat: HeartbeatSettings,
    calls: CallSettings,
    budget: BudgetSettings,
    competition: Boolean,
    stream: StreamSettings,
    zeromq: ZeroMqLinkSettings,
    gameControllerTrusted: TrustedSources = TrustedSources(Vector.empty),
    clockSync: ClockSyncSettings = ClockSyncSettings(),
    signingKey: Option[SigningKey] = None,
    newSessionKeepAlives: Int = 3,
    recording: RecordingSettings = RecordingSettings.Off,
    teamMessages: TeamMessageSettings = TeamMessageSettings(),
    monitor: Option[MonitorSettings] = None,
    gameControllerMaxDatagramsPerSecond: Int = 500,
    snapshotTimeout: FiniteDuration = 1.second,
    robotBacklog: Int = 256,
    gatewayBacklog: Int = 1024,
    supervision: SupervisionSettings = SupervisionSettings(),
    gateOpenAfter: FiniteDuration = 3.seconds,
    maxTrustedRange: Int = 32
) {
  require(
    gateOpenAfter >= 1.second && gateOpenAfter <= 1.minute,
    "game-controller.gate-open-after must be 1 s to 60 s (longer than the GameController's 500 ms interval)"
  )
  require(maxTrustedRange >= 1 && maxTrustedRange <= 32,
    "game-controller.max-trusted-range must be an IPv4 prefix length from 1 to 32 (32: a single address)")
  require(
    !competition || gameControllerTrusted.subnets.forall(TrustedSources.narrowEnough(_, maxTrustedRange)),
    s"competition mode refuses a trusted GameController range wider than /$maxTrustedRange " +
      s"(game-controller.trusted-sources = ${gameControllerTrusted.describe}): on a shared WiFi anyone in the range " +
      "could start or end the game for the gateway. Name the GameController's own address, or confirm the range's " +
      "width in game-controller.max-trusted-range (docs/protocol.md 10.7)"
  )
  require(gameControllerMaxDatagramsPerSecond > 0, "game-controller.max-datagrams-per-second must be positive")
  require(robotBacklog >= 1 && robotBacklog <= 100000, "link.robot-backlog must be between 1 and 100000")
  require(gatewayBacklog >= 1 && gatewayBacklog <= 100000, "link.gateway-backlog must be between 1 and 100000")
  require(snapshotTimeout >= 10.millis && snapshotTimeout <= 1.minute,
    "snapshot-timeout must be between 10 ms and 1 min")
  monitor.foreach { _ =>
    val conflicts = MonitorRole.conflicts(robots, bindAddress)
    require(conflicts.isEmpty, conflicts.mkString("; "))
    require(gameControllerEnabled, "game-controller.monitor needs game-controller.enabled")
  }
  require(newSessionKeepAlives >= 1 && newSessionKeepAlives <= 20, "new-session.keep-alives must be between 1 and 20")
  require(robotPort >= 0 && robotPort <= 65535, s"link.robot-port $robotPort is not a UDP port")
  require(robotReceivePort > 0 && robotReceivePort <= 65535,
    s"link.robot-receive-port $robotReceivePort is not a UDP port")
  require(gameControllerPort >= 0 && gameControllerPort <= 65535,
    s"game-controller.port $gameControllerPort is not a UDP port")
  require(robots.map(_.robotId).distinct.size == robots.size, "robots: every robot id may appear only once")
  require(
    !(competition && gameControllerEnabled && !gameControllerTrusted.configured),
    "competition mode needs game-controller.trusted-sources (the GameController's address or subnet, e.g. " +
      "[\"10.0.0.0/24\"]; env NAOGATEWAY_GAMECONTROLLER_TRUSTED): otherwise anyone on the WiFi could start or end " +
      "the game"
  )
  // A robot is known by its IP address (the gateway's routing), so two robots cannot share one.
  require(robots.map(_.address.getAddress).distinct.size == robots.size,
    "robots: every robot address may appear only once")
  require(
    robots.map(_.robotId).intersect(zeromq.robots.map(_.robotId)).isEmpty,
    "a robot id may be a UDP robot (robots) or a ZeroMQ robot (zeromq.robots), not both"
  )
  require(
    signingKey.isDefined || !robots.exists(_.signing == RobotSigning.Required),
    s"robots: robot ${robots.find(_.signing == RobotSigning.Required).fold("")(_.robotId.toString)} has signing = " +
      s"required, " +
      "but no signing key is set (signing.key, env NAOGATEWAY_SIGNING_KEY: the team key as 32 to 128 hexadecimal " +
      "digits)"
  )

  /** Whether robot `robotId`'s frames must be signed: a configured robot's own setting; any other robot (a discovered
    * one) must sign exactly when a team key is set.
    */
  def signingOf(robotId: Int): RobotSigning =
    robots.find(_.robotId == robotId).fold(RobotSigning.defaultFor(signingKey))(_.signing)
}

/** Reading and validating the settings. */
object GatewaySettings {

  /** The settings of this actor system's configuration. */
  def apply(system: ActorSystem[_]): GatewaySettings = fromConfig(system.settings.config.getConfig("naogateway"))

  /** The settings of a `naogateway` config block; invalid values fail with a message naming the key. */
  def fromConfig(c: Config): GatewaySettings = {
    val link = c.getConfig("link")
    val gc = c.getConfig("game-controller")
    val relay = c.getConfig("fu-remote-relay")
    val hb = c.getConfig("heartbeat")
    val calls = c.getConfig("calls")
    val budget = c.getConfig("budget")
    val stream = c.getConfig("stream")
    val zeroMq = c.getConfig("zeromq")
    val discovery = c.getConfig("discovery")
    // One name per concept: the old key is not read beside the new one, but named, so an old config fails clearly.
    require(!c.hasPath("discover-from-keep-alive"), "discover-from-keep-alive is now discovery.enabled")
    def duration(cfg: Config, key: String): FiniteDuration = cfg.getDuration(key).toScala
    val heartbeat = HeartbeatSettings(
      duration(hb, "keep-alive-interval"),
      duration(hb, "quiet-after"),
      duration(hb, "probe-timeout"),
      hb.getInt("chances"),
      duration(hb, "quality-window"),
      hb.getDouble("degraded-below"),
      hb.getDouble("good-above"),
      duration(hb, "probe-backoff-max"),
      duration(hb, "reader-grace")
    )
    val zeroMqHeartbeat = zeroMq.getConfig("heartbeat")
    val teamKey = signingKey(c)
    GatewaySettings(
      bindAddress = link.getString("bind-address"),
      robotPort = link.getInt("robot-port"),
      robotReceivePort = link.getInt("robot-receive-port"),
      gameControllerEnabled = gc.getBoolean("enabled"),
      gameControllerBindAddress = gc.getString("bind-address"),
      gameControllerPort = gc.getInt("port"),
      gameControllerReuseAddress = gc.getBoolean("reuse-address"),
      relay =
        if (relay.getBoolean("enabled")) Some(new InetSocketAddress(relay.getString("address"), relay.getInt("port")))
        else None,
      robots = c.getConfigList("robots").asScala.toVector.map { r =>
        // `port` is the older name of `receive-port`; both mean where the robot listens, never where it sends from.
        val port =
          if (r.hasPath("receive-port")) r.getInt("receive-port")
          else if (r.hasPath("port")) r.getInt("port")
          else link.getInt("robot-receive-port")
        require(port > 0 && port <= 65535, s"robots: robot ${r.getInt("id")}: receive-port $port is not a UDP port")
        // With a team key, a robot signs unless its entry says `signing = off` by name (docs/protocol.md 6.7).
        val signing =
          if (!r.hasPath("signing")) RobotSigning.defaultFor(teamKey)
          else RobotSigning.parse(r.getString("signing")).fold(
            e => throw new IllegalArgumentException(s"robots: robot ${r.getInt("id")}: $e"), identity)
        StaticRobot(r.getInt("id"), new InetSocketAddress(r.getString("address"), port), signing)
      },
      discovery = DiscoverySettings(
        enabled = discovery.getBoolean("enabled"),
        maxRobots = discovery.getInt("max-robots"),
        forgetUnreachedAfter = duration(discovery, "forget-unreached-after"),
        forgetOfflineAfter = duration(discovery, "forget-offline-after")
      ),
      heartbeat = heartbeat,
      calls =
        CallSettings(duration(calls, "timeout"), calls.getInt("idempotent-retries"), calls.getInt("stash-capacity")),
      budget = BudgetSettings(
        budget.getInt("team-bytes-per-second"),
        budget.getInt("robot-bytes-per-second"),
        budget.getDouble("warn-at"),
        budget.getDouble("probe-share"),
        budget.getInt("queue-capacity")
      ),
      competition = c.getBoolean("competition.enabled"),
      stream = StreamSettings(
        window = stream.getInt("window"),
        maxSeq = stream.getInt("max-seq"),
        honourSkipNotices = stream.getBoolean("honour-skip-notices")
      ),
      zeromq = ZeroMqLinkSettings(
        robots = zeroMq.getConfigList("robots").asScala.toVector.map(r =>
          ZeroMqRobot(r.getInt("id"), r.getString("endpoint"))),
        statusInterval = duration(zeroMq, "status-interval"),
        statusTimeout = duration(zeroMq, "status-timeout"),
        sendQueue = zeroMq.getInt("send-queue"),
        pollTimeout = duration(zeroMq, "poll-timeout"),
        handshakeTimeout = duration(zeroMq, "handshake-timeout"),
        // A REP robot answers one call at a time, so a posture motion holds back probes and status polls:
        // its liveness timing is its own, and the keep-alive it is judged by is the status poll.
        heartbeat = heartbeat.copy(
          keepAliveInterval = duration(zeroMq, "status-interval"),
          quietAfter = duration(zeroMqHeartbeat, "quiet-after"),
          probeTimeout = duration(zeroMqHeartbeat, "probe-timeout"),
          chances = zeroMqHeartbeat.getInt("chances")
        )
      ),
      gameControllerTrusted = trustedSources(gc),
      clockSync = ClockSyncSettings(duration(c.getConfig("clock-sync"), "window")),
      signingKey = teamKey,
      newSessionKeepAlives = c.getInt("new-session.keep-alives"),
      recording = RecordingSettings.fromConfig(c.getConfig("recording")),
      teamMessages = {
        val t = gc.getConfig("team-messages")
        TeamMessageSettings(
          t.getInt("team-number"),
          t.getInt("max-bytes"),
          t.getInt("per-game"),
          t.getInt("per-extra-minute"),
          t.getDuration("rate-window").getSeconds.toInt,
          t.getInt("max-datagrams-per-second"),
          t.getInt("per-extra-time")
        )
      },
      gameControllerMaxDatagramsPerSecond = gc.getInt("max-datagrams-per-second"),
      gateOpenAfter = duration(gc, "gate-open-after"),
      maxTrustedRange = gc.getInt("max-trusted-range"),
      snapshotTimeout = duration(c, "snapshot-timeout"),
      robotBacklog = link.getInt("robot-backlog"),
      gatewayBacklog = link.getInt("gateway-backlog"),
      supervision = SupervisionSettings(
        RestartBackoff.fromConfig(c, "supervision.outbox"),
        RestartBackoff.fromConfig(c, "supervision.robot"),
        RestartBackoff.fromConfig(c, "supervision.robot-children")
      ),
      monitor = {
        val m = gc.getConfig("monitor")
        if (!m.getBoolean("enabled")) None
        else {
          val address = m.getString("address").trim
          require(address.nonEmpty,
            "game-controller.monitor.address: the GameController's address is needed for the monitor role")
          Some(MonitorSettings(new InetSocketAddress(address, m.getInt("request-port")), m.getInt("status-port"),
              duration(m, "request-interval"), duration(m, "true-state-fresh")))
        }
      }
    )
  }

  /** `signing.key`: empty for none; a message about a bad key names its length, never its digits. */
  private def signingKey(c: Config): Option[SigningKey] = {
    val hex = if (c.hasPath("signing.key")) c.getString("signing.key").trim else ""
    if (hex.isEmpty) None
    else Some(SigningKey.fromHex(hex).fold(
        e => throw new IllegalArgumentException(s"signing.key (env NAOGATEWAY_SIGNING_KEY): $e"), identity))
  }

  /** `game-controller.trusted-sources`: a list of addresses or subnets, or one comma-separated string (the env form).
    */
  private def trustedSources(gc: Config): TrustedSources = {
    val key = "trusted-sources"
    val texts =
      if (!gc.hasPath(key)) Vector.empty
      else if (gc.getValue(key).valueType == com.typesafe.config.ConfigValueType.STRING)
        gc.getString(key).split(",").toVector.map(_.trim).filter(_.nonEmpty)
      else gc.getStringList(key).asScala.toVector
    TrustedSources(texts.map(t =>
        Subnet.parse(t).fold(e => throw new IllegalArgumentException(s"game-controller.$key: $e"), identity)))
  }
}
