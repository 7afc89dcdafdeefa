package apps

import java.net.InetAddress

import scala.jdk.CollectionConverters._
import scala.util.Try

import com.typesafe.config.Config

/** How a door's `enabled` key reads: `on` and `off` decide by name, `auto` by the robots served (see [[Doors.open]]).
  */
sealed abstract class DoorSwitch(val name: String) extends Product with Serializable

/** The three values of a door's `enabled` key. */
object DoorSwitch {

  /** Served whatever robots are configured. */
  case object On extends DoorSwitch("on")

  /** Never served. */
  case object Off extends DoorSwitch("off")

  /** Served beside simulated robots only, never while real robots are configured. */
  case object Auto extends DoorSwitch("auto")

  /** The switch `text` names: `on`/`true`/`yes`, `off`/`false`/`no` (HOCON's truth values) or `auto`. */
  def parse(text: String): Either[String, DoorSwitch] = text.trim.toLowerCase match {
    case "on" | "true" | "yes"  => Right(On)
    case "off" | "false" | "no" => Right(Off)
    case "auto"                 => Right(Auto)
    case other                  => Left(s"'$other' is not on, off or auto")
  }

  /** The switch at `key` of `c` (a door's block, whose own path is `path`); a value that is none of the three names the
    * whole key in the error.
    */
  def read(c: Config, key: String, path: String): DoorSwitch =
    parse(c.getString(key)).fold(e => throw new IllegalArgumentException(s"$path.$key: $e"), identity)
}

/** The rules every door follows (the datagram door, the ZeroMQ endpoint, the web view: the ways into the gateway beside
  * the cluster and the loopback-only control port). A door is on for real robots only when the config names it on, and
  * a door reachable from other machines needs a token: the web view has one; the datagram door and the ZeroMQ endpoint
  * have none and so are refused anywhere but on loopback (docs/zeromq.md, docs/web.md).
  */
object Doors {

  /** Whether a door with `switch` is served: `on` always, `off` never, `auto` only when `realRobots` is false. */
  def open(switch: DoorSwitch, realRobots: Boolean): Boolean = switch match {
    case DoorSwitch.On   => true
    case DoorSwitch.Off  => false
    case DoorSwitch.Auto => !realRobots
  }

  /** Whether the gateway node of `c` (a fully loaded launcher config) serves real robots: no simulated robots
    * (`apps.launcher.simulated-robots = 0`, which a replay sets too), or any robot listed in `naogateway.robots`. A
    * config without the launcher's block counts as real robots.
    */
  def realRobots(c: Config): Boolean =
    !c.hasPath("apps.launcher.simulated-robots") || c.getInt("apps.launcher.simulated-robots") == 0 ||
      (c.hasPath("naogateway.robots") && !c.getList("naogateway.robots").isEmpty)

  /** Whether `host` (a name or an address literal) is a loopback address only this machine reaches; a name that does
    * not resolve is not.
    */
  def loopback(host: String): Boolean = {
    val bare = host.stripPrefix("[").stripSuffix("]")
    bare != "*" && bare.nonEmpty && Try(InetAddress.getAllByName(bare).toVector).toOption.exists(a =>
      a.nonEmpty && a.forall(_.isLoopbackAddress))
  }

  /** The host of a ZeroMQ `tcp://host:port` endpoint (`*` for every interface); None for any other transport (ipc,
    * inproc), which is local to this machine.
    */
  def zeroMqHost(endpoint: String): Option[String] =
    Some(endpoint.trim).filter(_.startsWith("tcp://")).map { e =>
      val rest = e.stripPrefix("tcp://")
      // A `source;destination` endpoint binds the destination's part after the semicolon; ZeroMQ binds take host:port.
      val hostPort = rest.substring(rest.lastIndexOf(';') + 1)
      val colon = hostPort.lastIndexOf(':')
      if (colon < 0) hostPort else hostPort.substring(0, colon)
    }

  /** Every entry of a string list at `path`, trimmed; empty when the path is absent. */
  private[apps] def strings(c: Config, path: String): Vector[String] =
    if (c.hasPath(path)) c.getStringList(path).asScala.toVector.map(_.trim).filter(_.nonEmpty) else Vector.empty
}
