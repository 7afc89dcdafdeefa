package naogateway.gateway

import java.net.InetAddress

import scala.concurrent.duration._
import scala.jdk.DurationConverters._
import scala.util.Try

import com.typesafe.config.Config

/** Settings of the bus bridge (`naogateway.bus-bridge`, docs/protocol.md 6.9): each online robot's Dynamixel bus as a
  * TCP byte stream on loopback, at `basePort + robot id`.
  *
  * @param requestTimeout
  *   how long a request waits for the robot's reply before the tool gets nothing for it (its own timeout then fires)
  */
final case class BusBridgeSettings(
    enabled: Boolean = false,
    bindAddress: String = "127.0.0.1",
    basePort: Int = BusBridgeSettings.DefaultBasePort,
    requestTimeout: FiniteDuration = 1.second
) {
  require(basePort > 0 && basePort <= 65535, s"naogateway.bus-bridge.base-port $basePort is not a TCP port")
  require(requestTimeout > Duration.Zero, "naogateway.bus-bridge.request-timeout must be positive")
  // The bridge has no token: like the datagram door and the ZeroMQ endpoint it is refused anywhere but on loopback.
  require(
    BusBridgeSettings.loopback(bindAddress),
    s"naogateway.bus-bridge.bind-address \"$bindAddress\" is not a loopback address: the bus bridge has no token, so " +
      "it is refused anywhere but on loopback (127.0.0.1 or ::1)"
  )

  /** The port of robot `robotId`'s bridge, if it is a TCP port. */
  def portOf(robotId: Int): Option[Int] = Some(basePort + robotId).filter(p => robotId >= 0 && p <= 65535)
}

/** Reading [[BusBridgeSettings]]. */
object BusBridgeSettings {

  /** 6100 + robot id: robot 2's bus at 127.0.0.1:6102. */
  val DefaultBasePort: Int = 6100

  /** Whether `host` names loopback addresses only. */
  def loopback(host: String): Boolean =
    Try(InetAddress.getAllByName(host.stripPrefix("[").stripSuffix("]")).toVector).toOption.exists(a =>
      host.nonEmpty && a.nonEmpty && a.forall(_.isLoopbackAddress))

  /** The settings at `naogateway.bus-bridge` of `c` (the `naogateway` block). */
  def fromConfig(c: Config): BusBridgeSettings = {
    val b = c.getConfig("bus-bridge")
    BusBridgeSettings(b.getBoolean("enabled"), b.getString("bind-address"), b.getInt("base-port"),
      b.getDuration("request-timeout").toScala)
  }
}
