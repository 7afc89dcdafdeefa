package naogateway.launcher

import java.net.{BindException, DatagramSocket, InetAddress, InetSocketAddress, ServerSocket}

import scala.jdk.CollectionConverters._
import scala.util.control.NonFatal
import scala.util.{Try, Using}

import com.typesafe.config.{Config, ConfigException, ConfigFactory, ConfigValueType}

import naogateway.gateway.GatewaySettings
import naogateway.gateway.recording.RecordingSettings
import naogateway.sim.FleetSettings
import robotmiddleware.MiddlewareSettings
import apps.{DoorSwitch, Doors, StatusPrinter}

/** What the launcher checks before it starts anything, and `robotctl doctor` checks of a config: the settings are
  * valid, the ports they name are free, the demo's robot addresses exist, no key is a typo. Each problem is one line
  * for the terminal that names the key or the port and the setting that changes it: a stack trace in a log file helps
  * no operator at the field.
  */
object Preflight {

  /** How a port is used: TCP (a server socket) or UDP. */
  sealed abstract class Transport(val name: String) extends Product with Serializable

  /** The transports. */
  object Transport {

    /** A listening TCP socket. */
    case object Tcp extends Transport("TCP")

    /** A bound UDP socket; `reuse` when the program binds with SO_REUSEADDR (another listener may share it). */
    final case class Udp(reuse: Boolean) extends Transport("UDP")
  }

  /** A port the configured gateway node binds: where, what for, and the setting (and variable) that moves it. A port
    * that is not `essential` leaves the gateway running without it (the GameController's: game state stays unknown).
    */
  final case class PortUse(transport: Transport, host: String, port: Int, purpose: String, setting: String,
      essential: Boolean = true) {

    /** One line: the port is taken by another program. */
    def inUse: String =
      s"port $port (${transport.name} on $host, $purpose) is in use by another program; stop that program or move " +
        s"the port with $setting"

    /** One line: the address to bind is not one of this machine's. */
    def noSuchAddress: String =
      s"$host is not an address of this machine ($purpose, port $port); change it with $setting"
  }

  /** Every port the gateway node of `c` binds (a fully loaded launcher config); port 0 (any free one) is left out. */
  def ports(c: Config): Vector[PortUse] = {
    val cluster =
      if (c.getString("akka.actor.provider") == "cluster")
        Vector(PortUse(
            Transport.Tcp,
            bindHost(c),
            c.getInt("akka.remote.artery.canonical.port"),
            "the cluster port of the gateway node, where apps join",
            "robotmiddleware.cluster.gateway-port (ROBOTS_GATEWAY_PORT)"
          ))
      else Vector.empty
    val control =
      if (c.getBoolean("apps.control.enabled"))
        apps.control.ControlProtocol.address(c.getString("apps.control.bind")).toOption.toVector.map { case (h, p) =>
          PortUse(Transport.Tcp, h, p, "the control port robotctl talks to", "apps.control.bind (NAOGATEWAY_CONTROL)")
        }
      else Vector.empty
    val zeromq =
      if (doorOpen(c, apps.zeromq.ZeroMqSettings.ConfigPath))
        Vector("bind" -> "the ZeroMQ request socket", "publish" -> "the ZeroMQ publish socket").flatMap {
          case (key, purpose) =>
            zeroMqTcp(c.getString(s"apps.zeromq.$key")).map { case (h, p) =>
              PortUse(Transport.Tcp, h, p, purpose, s"apps.zeromq.$key (NAOGATEWAY_ZEROMQ_${key.toUpperCase})")
            }
        }
      else Vector.empty
    val datagramDoor =
      if (doorOpen(c, apps.datagram.DatagramDoorSettings.ConfigPath))
        Vector(PortUse(
            Transport.Udp(reuse = false),
            c.getString("apps.datagram-door.bind-address"),
            c.getInt("apps.datagram-door.port"),
            "the datagram door",
            "apps.datagram-door.port (NAOGATEWAY_DATAGRAM_DOOR_PORT)"
          ))
      else Vector.empty
    val web =
      if (doorOpen(c, apps.web.WebSettings.ConfigPath))
        Vector(PortUse(Transport.Tcp, c.getString("apps.web.bind-address"), c.getInt("apps.web.port"),
            "the web view", "apps.web.port (NAOGATEWAY_WEB_PORT)", essential = false))
      else Vector.empty
    val robots = Vector(PortUse(
        Transport.Udp(reuse = false),
        c.getString("naogateway.link.bind-address"),
        c.getInt("naogateway.link.robot-port"),
        "the robots' port (FU-Remote's too: give FU-Remote another port and turn on naogateway.fu-remote-relay)",
        "naogateway.link.robot-port (NAOGATEWAY_ROBOT_PORT)"
      ))
    val gameController =
      if (c.getBoolean("naogateway.game-controller.enabled"))
        Vector(PortUse(
            Transport.Udp(c.getBoolean("naogateway.game-controller.reuse-address")),
            c.getString("naogateway.game-controller.bind-address"),
            c.getInt("naogateway.game-controller.port"),
            "the GameController's broadcasts",
            "naogateway.game-controller.port (NAOGATEWAY_GAMECONTROLLER_PORT) or " +
              "naogateway.game-controller.reuse-address",
            essential = false
          ))
      else Vector.empty
    (cluster ++ control ++ zeromq ++ datagramDoor ++ web ++ robots ++ gameController).filter(_.port > 0)
  }

  private def bindHost(c: Config): String = {
    val b = Try(c.getString("akka.remote.artery.bind.hostname")).getOrElse("")
    if (b.nonEmpty) b else c.getString("akka.remote.artery.canonical.hostname")
  }

  // "tcp://127.0.0.1:5555" as host and port; a wildcard port ("*") or another transport binds nothing checkable.
  private def zeroMqTcp(endpoint: String): Option[(String, Int)] =
    Some(endpoint).filter(_.startsWith("tcp://")).map(_.stripPrefix("tcp://")).flatMap(e =>
      apps.control.ControlProtocol.address(e).toOption)
      .map { case (h, p) => (if (h == "*") "0.0.0.0" else h, p) }

  /** What binding a port found: free, taken, or an address this machine does not have. */
  sealed trait Probe extends Product with Serializable

  /** The probe results. */
  object Probe {

    /** The port could be bound (and was let go at once). */
    case object Free extends Probe

    /** Another socket holds it. */
    case object InUse extends Probe

    /** The host is not an address of this machine. */
    case object NoSuchAddress extends Probe
  }

  /** Binds `use` for a moment, as the gateway node would, and lets it go. */
  def probe(use: PortUse): Probe =
    try {
      val address = new InetSocketAddress(InetAddress.getByName(use.host), use.port)
      use.transport match {
        case Transport.Tcp =>
          Using.resource(new ServerSocket()) { s => s.setReuseAddress(true); s.bind(address) }
        case Transport.Udp(reuse) =>
          Using.resource(new DatagramSocket(null: java.net.SocketAddress)) { s =>
            s.setReuseAddress(reuse); s.bind(address)
          }
      }
      Probe.Free
    } catch {
      case e: BindException if Option(e.getMessage).exists(_.toLowerCase.contains("assign")) => Probe.NoSuchAddress
      case _: BindException                                                                  => Probe.InUse
      case _: java.net.UnknownHostException                                                  => Probe.NoSuchAddress
    }

  /** One line for each port of `uses` that `probe` finds taken or unbindable. */
  def portProblems(uses: Seq[PortUse], probe: PortUse => Probe = Preflight.probe): Vector[String] =
    uses.toVector.flatMap { u =>
      probe(u) match {
        case Probe.Free          => None
        case Probe.InUse         => Some(u.inUse)
        case Probe.NoSuchAddress => Some(u.noSuchAddress)
      }
    }

  /** Reads every setting the gateway node reads at start, so a wrong key or value fails here, before any actor runs.
    * Throws what the settings throw (`ConfigException`, `IllegalArgumentException`); [[problem]] turns it into a line.
    */
  def validate(c: Config): Unit = {
    typesMatch(c)
    val gateway = GatewaySettings.fromConfig(c.getConfig("naogateway"))
    MiddlewareSettings.fromConfig(c.getConfig("robotmiddleware"))
    apps.control.ControlSettings.fromConfig(c.getConfig(apps.control.ControlSettings.ConfigPath))
    apps.zeromq.ZeroMqSettings.fromConfig(c.getConfig(apps.zeromq.ZeroMqSettings.ConfigPath),
      s"${apps.zeromq.ZeroMqSettings.ConfigPath}.dispatcher")
    Launcher.settings(c.getConfig("apps.launcher"))
    StatusPrinter.settings(c.getConfig("apps.launcher"))
    val _: RecordingSettings = gateway.recording
    doorRefusals(c).headOption.foreach(r => throw new IllegalArgumentException(r))
  }

  /** What an operator should know about the doors `c` opens: the web view off loopback (it passes on its token). */
  def doorWarnings(c: Config): Vector[String] = {
    val path = apps.web.WebSettings.ConfigPath
    Option.when(doorOpen(c, path)) {
      val web = apps.web.WebSettings.fromConfig(c.getConfig(path))
      Option.when(web.refusal.isEmpty && !Doors.loopback(web.bindAddress))(
        s"the web view listens on ${web.bindAddress}, not loopback: every machine that reaches it and has the token " +
          "(apps.web.token) can watch the robots")
    }.flatten.toVector
  }

  /** Whether the door configured at `path` (its `enabled` switch) is served by the gateway node of `c`. */
  def doorOpen(c: Config, path: String): Boolean =
    Doors.open(DoorSwitch.read(c.getConfig(path), "enabled", path), Doors.realRobots(c))

  /** Why each door that `c` opens must not serve: the datagram door and the ZeroMQ endpoint off loopback (they have no
    * token), the web view off loopback without its token.
    */
  def doorRefusals(c: Config): Vector[String] = {
    val zeromq = apps.zeromq.ZeroMqSettings.ConfigPath
    val door = apps.datagram.DatagramDoorSettings.ConfigPath
    val web = apps.web.WebSettings.ConfigPath
    Vector(
      Option.when(doorOpen(c, zeromq))(
        apps.zeromq.ZeroMqSettings.fromConfig(c.getConfig(zeromq), s"$zeromq.dispatcher").refusal).flatten,
      Option.when(doorOpen(c, door))(apps.datagram.DatagramDoorSettings.fromConfig(c.getConfig(door)).refusal).flatten,
      Option.when(doorOpen(c, web))(apps.web.WebSettings.fromConfig(c.getConfig(web)).refusal).flatten
    ).flatten
  }

  // Keys whose code reads another form than the reference's (a comma-separated string from the environment for a list).
  private val FlexibleKeys = Set("naogateway.game-controller.trusted-sources")

  /** Every value under the project's roots that its reference default gives a number, a truth value, an object or a
    * list reads as one. The settings would find a wrong type too, but name only the last part of its key; read here by
    * its whole path, the error names the whole key and where it was set.
    */
  def typesMatch(c: Config): Unit =
    ProjectRoots.filter(c.hasPath).foreach { root =>
      c.getConfig(root).entrySet().asScala.map(e => s"$root.${e.getKey}").toVector.sorted.foreach { path =>
        if (knownKeys.hasPath(path) && !FlexibleKeys(path))
          knownKeys.getValue(path).valueType() match {
            case ConfigValueType.NUMBER  => c.getNumber(path)
            case ConfigValueType.BOOLEAN => c.getBoolean(path)
            case ConfigValueType.LIST    => c.getList(path)
            case _                       => ()
          }
      }
    }

  /** One line naming the key and what is wrong with it, for a config problem; None for anything else. */
  def problem(e: Throwable): Option[String] = e match {
    case c: ConfigException => Some(s"config: ${c.getMessage}")
    case i: IllegalArgumentException =>
      Some(s"config: ${Option(i.getMessage).getOrElse("invalid value").stripPrefix("requirement failed: ")}")
    case _ => None
  }

  /** The demo's simulated robots each need a loopback address of their own (robots are told apart by IP address):
    * 127.0.0.11 and up. Linux has all of 127.0.0.0/8; macOS has only 127.0.0.1 unless told. One line saying exactly
    * what to do when `bindable` finds any missing.
    */
  def missingLoopback(simulatedRobots: Int, bindable: InetAddress => Boolean = loopbackBindable): Option[String] =
    if (simulatedRobots <= 0) None
    else {
      val settings =
        FleetSettings(new InetSocketAddress(InetAddress.getLoopbackAddress, 1), (1 to simulatedRobots).toVector)
      val missing = (0 until simulatedRobots).map(settings.addressOf).filterNot(bindable)
      missing.headOption.map { first =>
        val names = missing.map(_.getHostAddress)
        val shown = if (names.size <= 3) names.mkString(", ") else s"${names.head} to ${names.last}"
        s"the demo's $simulatedRobots simulated robots need loopback addresses of their own, and this machine lacks " +
          s"$shown " +
          s"(macOS has only 127.0.0.1): add them with " +
          s"`for i in $$(seq ${first.getAddress()(3) & 0xff} ${missing.last.getAddress()(3) & 0xff}); do sudo " +
          s"ifconfig lo0 alias 127.0.0.$$i up; done`, " +
          "or run without simulated robots (NAOGATEWAY_SIMULATED_ROBOTS=0)"
      }
    }

  /** Whether a UDP socket can be bound to `address` (any port). */
  def loopbackBindable(address: InetAddress): Boolean =
    try { Using.resource(new DatagramSocket(new InetSocketAddress(address, 0)))(_ => true) }
    catch { case NonFatal(_) => false }

  /** The config roots of this project, whose every key has a default in some reference (or launcher) file. */
  val ProjectRoots: Vector[String] = Vector("naogateway", "robotmiddleware", "apps")

  /** Keys under the project's roots that `c` sets but no reference file knows: most often a typo, which would otherwise
    * leave the default in force without a word. Lists (such as `naogateway.robots`) are leaves: their elements are
    * checked by the settings themselves.
    */
  def unknownKeys(c: Config, known: Config): Vector[String] =
    ProjectRoots.filter(c.hasPath).flatMap { root =>
      c.getConfig(root).entrySet().asScala.map(e => s"$root.${e.getKey}").toVector
    }.filterNot(path => known.hasPathOrNull(path) || knownPrefix(known, path)).sorted

  // A key below a list or below a value the reference leaves open (an object of anything) is not unknown.
  private def knownPrefix(known: Config, path: String): Boolean = {
    val parts = com.typesafe.config.ConfigUtil.splitPath(path).asScala.toVector
    (1 until parts.size).exists { n =>
      val prefix = com.typesafe.config.ConfigUtil.joinPath(parts.take(n).asJava)
      known.hasPathOrNull(prefix) && !known.getIsNull(prefix) &&
      known.getValue(prefix).valueType() == ConfigValueType.LIST
    }
  }

  /** Every key the project's reference files and the launcher's defaults know, resolved without the environment. */
  lazy val knownKeys: Config =
    ConfigFactory.parseResources(Launcher.DefaultsResource)
      .withFallback(ConfigFactory.parseResources(robotmiddleware.cluster.MiddlewareCluster.ConfigResource))
      .withFallback(ConfigFactory.defaultReference())
      .resolve()
}
