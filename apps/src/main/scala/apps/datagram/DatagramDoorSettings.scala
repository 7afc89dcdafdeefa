package apps.datagram

import scala.concurrent.duration._
import scala.jdk.DurationConverters._

import akka.actor.typed.ActorSystem
import com.typesafe.config.Config

/** Settings of the datagram door (`apps.datagram-door { ... }`). */
final case class DatagramDoorSettings(
    enabled: apps.DoorSwitch,
    bindAddress: String,
    port: Int,
    appName: String,
    priority: Int,
    requestTimeout: FiniteDuration,
    maxInFlight: Int,
    maxInFlightPerSender: Int,
    maxDatagramBytes: Int,
    dispatcher: String = "akka.actor.default-dispatcher"
) {
  require(bindAddress.nonEmpty, "datagram-door.bind-address must not be empty")
  require(port >= 0 && port <= 65535, "datagram-door.port must be between 0 and 65535")
  require(appName.nonEmpty, "datagram-door.app-name must not be empty")
  require(requestTimeout > Duration.Zero, "datagram-door.request-timeout must be positive")
  require(maxInFlight >= 1, "datagram-door.max-in-flight must be at least 1")
  require(maxInFlightPerSender >= 1 && maxInFlightPerSender <= maxInFlight,
    "datagram-door.max-in-flight-per-sender must be between 1 and max-in-flight")
  require(
    maxDatagramBytes >= 64 && maxDatagramBytes <= DatagramDoorSettings.MaxUdpPayload,
    s"datagram-door.max-datagram-bytes must be between 64 and ${DatagramDoorSettings.MaxUdpPayload}"
  )
  require(dispatcher.trim.nonEmpty, "datagram-door.dispatcher must name a dispatcher's config path")

  /** Why the door must not serve, if it must not: it has no token and UDP senders are not authenticated, so only this
    * machine may reach it.
    */
  def refusal: Option[String] =
    Option.when(!apps.Doors.loopback(bindAddress))(
      s"apps.datagram-door.bind-address $bindAddress is not loopback, and the datagram door has no token: it serves " +
        "this machine only (use the ZeroMQ endpoint through an SSH tunnel, or the cluster, from other machines)")
}

/** Reading the settings. */
object DatagramDoorSettings {

  /** Where the settings live in the configuration. */
  val ConfigPath: String = "apps.datagram-door"

  /** The largest payload of a UDP datagram over IPv4. */
  val MaxUdpPayload: Int = 65507

  /** The settings of this system's configuration. */
  def apply(system: ActorSystem[_]): DatagramDoorSettings = fromConfig(system.settings.config.getConfig(ConfigPath))

  /** The settings of an `apps.datagram-door` block. */
  def fromConfig(c: Config): DatagramDoorSettings = DatagramDoorSettings(
    enabled = apps.DoorSwitch.read(c, "enabled", ConfigPath),
    bindAddress = c.getString("bind-address"),
    port = c.getInt("port"),
    appName = c.getString("app-name"),
    priority = c.getInt("priority"),
    requestTimeout = c.getDuration("request-timeout").toScala,
    maxInFlight = c.getInt("max-in-flight"),
    maxInFlightPerSender = c.getInt("max-in-flight-per-sender"),
    maxDatagramBytes = c.getInt("max-datagram-bytes"),
    dispatcher = c.getString("dispatcher")
  )
}
