package apps.web

import java.net.InetAddress

import scala.concurrent.duration._
import scala.jdk.DurationConverters._

import akka.actor.typed.ActorSystem
import com.typesafe.config.Config

/** Settings of the web view (`apps.web { ... }`, docs/web.md).
  *
  * @param token
  *   the access token every WebSocket must present (`?token=`); empty for none, which only a loopback address may go
  *   without
  */
final case class WebSettings(
    enabled: apps.DoorSwitch,
    bindAddress: String,
    port: Int,
    token: String,
    pushInterval: FiniteDuration,
    sampleInterval: FiniteDuration,
    historyPoints: Int,
    events: Int,
    maxClients: Int,
    clientBuffer: Int,
    gridInterval: FiniteDuration,
    control: WebSettings.Control,
    allowedOrigins: Vector[String] = Vector.empty
) {
  require(port >= 0 && port <= 65535, "apps.web.port must be 0 to 65535")
  require(pushInterval >= 50.millis, "apps.web.push-interval must be at least 50 ms")
  require(sampleInterval >= pushInterval, "apps.web.sample-interval must be at least push-interval")
  require(historyPoints >= 2 && historyPoints <= 10000, "apps.web.history-points must be 2 to 10000")
  require(events >= 1 && events <= 10000, "apps.web.events must be 1 to 10000")
  require(maxClients >= 1 && maxClients <= 1000, "apps.web.max-clients must be 1 to 1000")
  require(clientBuffer >= 1 && clientBuffer <= 1000, "apps.web.client-buffer must be 1 to 1000")
  require(gridInterval >= pushInterval, "apps.web.grid-interval must be at least push-interval")
  require(control.appName.nonEmpty, "apps.web.control.app-name must not be empty")
  require(control.deadman >= 200.millis, "apps.web.control.deadman must be at least 200 ms")

  require(
    allowedOrigins.forall(o => WebOrigin.parse(o).isDefined),
    s"apps.web.allowed-origins: each entry is scheme://host[:port], got ${allowedOrigins.mkString(", ")}"
  )

  /** Whether the bind address is a loopback one, reachable from this machine only. */
  def loopbackOnly: Boolean = InetAddress.getByName(bindAddress).isLoopbackAddress

  /** Why these settings must not serve, if they must not: a view reachable from other machines needs a token, so a
    * stranger on the field's network cannot watch (or, with the control panel, steer).
    */
  def refusal: Option[String] =
    Option.when(token.isEmpty && !loopbackOnly)(
      s"apps.web.bind-address $bindAddress is not loopback, so apps.web.token must be set")
}

/** Reading the settings. */
object WebSettings {

  /** The control panel's settings (`apps.web.control`). */
  final case class Control(enabled: Boolean, appName: String, priority: Int, deadman: FiniteDuration)

  /** Where the settings live in the configuration. */
  val ConfigPath: String = "apps.web"

  /** The settings of this system's configuration. */
  def apply(system: ActorSystem[_]): WebSettings = fromConfig(system.settings.config.getConfig(ConfigPath))

  /** The settings of an `apps.web` block. */
  def fromConfig(c: Config): WebSettings =
    WebSettings(
      enabled = apps.DoorSwitch.read(c, "enabled", ConfigPath),
      bindAddress = c.getString("bind-address"),
      port = c.getInt("port"),
      token = c.getString("token").trim,
      pushInterval = c.getDuration("push-interval").toScala,
      sampleInterval = c.getDuration("sample-interval").toScala,
      historyPoints = c.getInt("history-points"),
      events = c.getInt("events"),
      maxClients = c.getInt("max-clients"),
      clientBuffer = c.getInt("client-buffer"),
      gridInterval = c.getDuration("grid-interval").toScala,
      control = Control(c.getBoolean("control.enabled"), c.getString("control.app-name"), c.getInt("control.priority"),
        c.getDuration("control.deadman").toScala),
      allowedOrigins = apps.Doors.strings(c, "allowed-origins")
    )
}
