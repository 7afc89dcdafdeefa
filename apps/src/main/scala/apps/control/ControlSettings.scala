package apps.control

import scala.concurrent.duration._
import scala.jdk.DurationConverters._

import akka.actor.typed.ActorSystem
import com.typesafe.config.Config

/** Settings of the control port that robotctl talks to (`apps.control { ... }`). */
final case class ControlSettings(
    enabled: Boolean,
    host: String,
    port: Int,
    appName: String,
    priority: Int,
    maxConnections: Int,
    requestTimeout: FiniteDuration,
    answerTimeout: FiniteDuration,
    linkStatsTimeout: FiniteDuration,
    maxWatch: FiniteDuration
) {
  require(appName.nonEmpty, "control.app-name must not be empty")
  require(maxConnections >= 1, "control.max-connections must be at least 1")
  require(requestTimeout > Duration.Zero, "control.request-timeout must be positive")
  require(answerTimeout > Duration.Zero, "control.answer-timeout must be positive")
  require(linkStatsTimeout > Duration.Zero && linkStatsTimeout < answerTimeout,
    "control.link-stats-timeout must be positive and below answer-timeout")
  require(maxWatch >= 1.second, "control.max-watch must be at least 1 s")
}

/** Reading the settings. */
object ControlSettings {

  /** Where the settings live in the configuration. */
  val ConfigPath: String = "apps.control"

  /** The settings of this system's configuration. */
  def apply(system: ActorSystem[_]): ControlSettings = fromConfig(system.settings.config.getConfig(ConfigPath))

  /** The settings of an `apps.control` block. */
  def fromConfig(c: Config): ControlSettings = {
    val (host, port) = ControlProtocol.address(c.getString("bind")).fold(
      e => throw new IllegalArgumentException(s"control.bind: $e"), identity)
    ControlSettings(
      enabled = c.getBoolean("enabled"),
      host = host,
      port = port,
      appName = c.getString("app-name"),
      priority = c.getInt("priority"),
      maxConnections = c.getInt("max-connections"),
      requestTimeout = c.getDuration("request-timeout").toScala,
      answerTimeout = c.getDuration("answer-timeout").toScala,
      linkStatsTimeout = c.getDuration("link-stats-timeout").toScala,
      maxWatch = c.getDuration("max-watch").toScala
    )
  }
}
