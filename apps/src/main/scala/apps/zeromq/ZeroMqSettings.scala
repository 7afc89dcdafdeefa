package apps.zeromq

import scala.concurrent.duration._
import scala.jdk.DurationConverters._

import akka.actor.typed.ActorSystem
import com.typesafe.config.Config

/** Settings of the ZeroMQ endpoint (`apps.zeromq { ... }`). */
final case class ZeroMqSettings(
    enabled: apps.DoorSwitch,
    bind: String,
    publish: String,
    appName: String,
    priority: Int,
    requestTimeout: FiniteDuration,
    maxInFlight: Int,
    pollTimeout: FiniteDuration,
    dispatcher: String
) {
  require(bind.nonEmpty && publish.nonEmpty, "zeromq.bind and zeromq.publish must be ZeroMQ endpoints")
  require(bind != publish || bind.endsWith(":*"),
    "zeromq.bind and zeromq.publish must differ (or both take a free port, :*)")
  require(appName.nonEmpty, "zeromq.app-name must not be empty")
  require(requestTimeout > Duration.Zero, "zeromq.request-timeout must be positive")
  require(maxInFlight >= 1, "zeromq.max-in-flight must be at least 1")
  require(pollTimeout >= 1.milli && pollTimeout <= 1.second, "zeromq.poll-timeout must be between 1 ms and 1 s")

  /** Why the endpoint must not serve, if it must not: it has no token (no CURVE, no ZAP), so only this machine may
    * reach its TCP sockets.
    */
  def refusal: Option[String] =
    Vector("bind" -> bind, "publish" -> publish).collectFirst {
      case (key, endpoint) if apps.Doors.zeroMqHost(endpoint).exists(h => !apps.Doors.loopback(h)) =>
        s"apps.zeromq.$key $endpoint is not loopback, and the ZeroMQ endpoint has no token: it serves this machine " +
          "only (reach it from other machines through an SSH tunnel)"
    }
}

/** Reading the settings. */
object ZeroMqSettings {

  /** Where the settings live in the configuration. */
  val ConfigPath: String = "apps.zeromq"

  /** The settings of this system's configuration. */
  def apply(system: ActorSystem[_]): ZeroMqSettings =
    fromConfig(system.settings.config.getConfig(ConfigPath), s"$ConfigPath.dispatcher")

  /** The settings of an `apps.zeromq` block whose dispatcher is configured at `dispatcherPath`. */
  def fromConfig(c: Config, dispatcherPath: String): ZeroMqSettings = ZeroMqSettings(
    enabled = apps.DoorSwitch.read(c, "enabled", ConfigPath),
    bind = c.getString("bind"),
    publish = c.getString("publish"),
    appName = c.getString("app-name"),
    priority = c.getInt("priority"),
    requestTimeout = c.getDuration("request-timeout").toScala,
    maxInFlight = c.getInt("max-in-flight"),
    pollTimeout = c.getDuration("poll-timeout").toScala,
    dispatcher = dispatcherPath
  )
}
