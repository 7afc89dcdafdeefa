package robotmiddleware

import scala.concurrent.duration._
import scala.jdk.DurationConverters._

import akka.actor.typed.ActorSystem
import com.typesafe.config.Config

import naogateway.access.RestartBackoff

/** Settings of the middleware (`robotmiddleware { ... }`). */
final case class MiddlewareSettings(
    lowBattery: Double,
    batteryOk: Double,
    walkRefresh: FiniteDuration,
    callTimeout: FiniteDuration,
    postureTimeout: FiniteDuration,
    linkStatsInterval: FiniteDuration,
    pendingLimit: Int,
    batteryReadings: Int = 5,
    lookupTimeout: FiniteDuration = 3.seconds,
    askMargin: FiniteDuration = 1.second,
    guardRestart: RestartBackoff = RestartBackoff(200.millis, 5.seconds, 0.2),
    clientAskMargin: FiniteDuration = 5.seconds,
    clientFindRetry: FiniteDuration = 200.millis,
    dispatcher: String = MiddlewareSettings.DefaultDispatcher,
    servoLimits: ServoLimits = ServoLimits(),
    limits: ArgumentLimits = ArgumentLimits.Default
) {
  require(lowBattery < batteryOk, "safety.low-battery must be below safety.battery-ok")
  require(walkRefresh > Duration.Zero && walkRefresh < 500.millis,
    "walk-refresh must be inside the robot's 500 ms walk lease")
  require(callTimeout > Duration.Zero && postureTimeout >= callTimeout, "need 0 < call-timeout <= posture-timeout")
  require(linkStatsInterval > Duration.Zero, "link-stats-interval must be positive")
  require(pendingLimit >= 1, "pending-limit must be at least 1")
  require(batteryReadings >= 1 && batteryReadings <= 100, "safety.battery-readings must be from 1 to 100")
  require(lookupTimeout > Duration.Zero, "lookup-timeout must be positive")
  require(askMargin > Duration.Zero, "ask-margin must be positive")
  require(clientAskMargin > Duration.Zero, "client.ask-margin must be positive")
  require(clientFindRetry >= 10.millis, "client.find-retry must be at least 10 ms")
  require(dispatcher.trim.nonEmpty, "dispatcher must name a dispatcher's config path")
}

/** Reading the settings. */
object MiddlewareSettings {

  /** Akka's own dispatcher: where the middleware runs unless the node puts it beside the gateway's robot actors. */
  val DefaultDispatcher: String = "akka.actor.default-dispatcher"

  /** The settings of this system's configuration. */
  def apply(system: ActorSystem[_]): MiddlewareSettings =
    fromConfig(system.settings.config.getConfig("robotmiddleware"))

  /** The settings of a `robotmiddleware` block. */
  def fromConfig(c: Config): MiddlewareSettings = MiddlewareSettings(
    c.getDouble("safety.low-battery"),
    c.getDouble("safety.battery-ok"),
    c.getDuration("walk-refresh").toScala,
    c.getDuration("call-timeout").toScala,
    c.getDuration("posture-timeout").toScala,
    c.getDuration("link-stats-interval").toScala,
    c.getInt("pending-limit"),
    c.getInt("safety.battery-readings"),
    c.getDuration("lookup-timeout").toScala,
    c.getDuration("ask-margin").toScala,
    RestartBackoff.fromConfig(c, "supervision.guard"),
    c.getDuration("client.ask-margin").toScala,
    c.getDuration("client.find-retry").toScala,
    c.getString("dispatcher"),
    ServoLimits(c.getInt("servos.hot"), c.getDouble("servos.low-voltage")),
    ArgumentLimits(c.getDouble("walk-limits.speed"), c.getDouble("walk-limits.turn"))
  )
}
