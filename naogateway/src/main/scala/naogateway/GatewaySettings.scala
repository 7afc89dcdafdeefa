package naogateway

import java.net.InetSocketAddress

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.jdk.DurationConverters._

import akka.actor.typed.ActorSystem
import com.typesafe.config.Config

import naogateway.wire.stream.StreamSettings

/** A robot known from configuration: its id and where it receives. */
final case class StaticRobot(robotId: Int, address: InetSocketAddress)

/** Liveness settings of the heartbeat. */
final case class HeartbeatSettings(
    keepAliveInterval: FiniteDuration,
    quietAfter: FiniteDuration,
    probeTimeout: FiniteDuration,
    chances: Int,
    qualityWindow: FiniteDuration,
    degradedBelow: Double,
    goodAbove: Double
) {
  require(keepAliveInterval > Duration.Zero, "heartbeat.keep-alive-interval must be positive")
  require(quietAfter >= keepAliveInterval, "heartbeat.quiet-after must be at least one keep-alive interval")
  require(probeTimeout > Duration.Zero, "heartbeat.probe-timeout must be positive")
  require(chances >= 1, "heartbeat.chances must be at least 1")
  require(qualityWindow >= keepAliveInterval * 2, "heartbeat.quality-window must cover at least two keep-alives")
  require(0 < degradedBelow && degradedBelow <= goodAbove && goodAbove <= 1, "need 0 < degraded-below <= good-above <= 1")

  /** Worst-case time from the last keep-alive to offline. */
  def detection: FiniteDuration = quietAfter + probeTimeout * chances.toLong
}

/** Call settings: timeout, retries of idempotent calls, and the bound of waiting commands. */
final case class CallSettings(timeout: FiniteDuration, idempotentRetries: Int, stashCapacity: Int) {
  require(timeout > Duration.Zero, "calls.timeout must be positive")
  require(idempotentRetries >= 0, "calls.idempotent-retries must not be negative")
  require(stashCapacity >= 1, "calls.stash-capacity must be at least 1")
}

/** The team's traffic budget. */
final case class BudgetSettings(teamBytesPerSecond: Int, robotBytesPerSecond: Int, warnAt: Double) {
  require(teamBytesPerSecond >= 1400, "budget.team-bytes-per-second must allow at least one datagram")
  require(robotBytesPerSecond == 0 || robotBytesPerSecond >= 1400, "budget.robot-bytes-per-second is 0 (none) or >= 1400")
  require(warnAt > 0 && warnAt <= 1, "budget.warn-at must be in (0, 1]")
}

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
    discoverFromKeepAlive: Boolean,
    heartbeat: HeartbeatSettings,
    calls: CallSettings,
    budget: BudgetSettings,
    competition: Boolean,
    stream: StreamSettings
) {
  require(robotPort >= 0 && robotPort <= 65535, s"link.robot-port $robotPort is not a UDP port")
  require(robotReceivePort > 0 && robotReceivePort <= 65535, s"link.robot-receive-port $robotReceivePort is not a UDP port")
  require(gameControllerPort >= 0 && gameControllerPort <= 65535, s"game-controller.port $gameControllerPort is not a UDP port")
  require(robots.map(_.robotId).distinct.size == robots.size, "robots: every robot id may appear only once")
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
    def duration(cfg: Config, key: String): FiniteDuration = cfg.getDuration(key).toScala
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
        val port = if (r.hasPath("port")) r.getInt("port") else link.getInt("robot-receive-port")
        StaticRobot(r.getInt("id"), new InetSocketAddress(r.getString("address"), port))
      },
      discoverFromKeepAlive = c.getBoolean("discover-from-keep-alive"),
      heartbeat = HeartbeatSettings(
        duration(hb, "keep-alive-interval"),
        duration(hb, "quiet-after"),
        duration(hb, "probe-timeout"),
        hb.getInt("chances"),
        duration(hb, "quality-window"),
        hb.getDouble("degraded-below"),
        hb.getDouble("good-above")
      ),
      calls = CallSettings(duration(calls, "timeout"), calls.getInt("idempotent-retries"), calls.getInt("stash-capacity")),
      budget = BudgetSettings(budget.getInt("team-bytes-per-second"), budget.getInt("robot-bytes-per-second"),
        budget.getDouble("warn-at")),
      competition = c.getBoolean("competition.enabled"),
      stream = StreamSettings(
        window = stream.getInt("window"),
        maxSeq = stream.getInt("max-seq"),
        honourSkipNotices = stream.getBoolean("honour-skip-notices")
      )
    )
  }
}
