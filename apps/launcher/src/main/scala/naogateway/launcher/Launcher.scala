package naogateway.launcher

import java.io.File
import java.net.{InetAddress, InetSocketAddress}
import java.nio.file.Paths

import scala.concurrent.duration._
import scala.jdk.DurationConverters._
import scala.util.control.NonFatal
import scala.util.{Failure, Success}

import akka.actor.CoordinatedShutdown
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, ActorSystem, Behavior}
import com.typesafe.config.{Config, ConfigFactory}

import naogateway.access.GatewayAccess
import naogateway.gateway.{Gateway, GatewayReadView, GatewaySettings}
import naogateway.gateway.link.Replay
import naogateway.sim.{Fleet, FleetSettings}
import robotmiddleware.cluster.MiddlewareCluster
import robotmiddleware.{MiddlewareSettings, RobotClient, RobotMiddleware}
import apps.{BallFollower, Doors, StatusPrinter}
import naogateway.api.GatewayAddresses

/** `./sbt run`: gateway, middleware, simulated robots and the ball follower, with a live status view. */
object Launcher {

  /** The launcher's settings (`apps.launcher`). */
  final case class Settings(simulatedRobots: Int, ballFollowerRobot: Int, refresh: FiniteDuration) {
    require(simulatedRobots >= 0 && simulatedRobots <= 1000, "apps.launcher.simulated-robots must be 0 to 1000")
    require(refresh >= 50.millis, "apps.launcher.refresh must be at least 50 ms")
  }

  /** The settings of an `apps.launcher` block. */
  def settings(c: Config): Settings =
    Settings(c.getInt("simulated-robots"), c.getInt("ball-follower-robot"), c.getDuration("refresh").toScala)

  /** The resource with the launcher's defaults: below application.conf, above the references. */
  val DefaultsResource: String = "launcher.conf"

  /** The launcher's defaults (the demo's), unresolved: environment variables are read when the whole config is. */
  def defaults: Config = ConfigFactory.parseResources(DefaultsResource)

  /** The config file given as argument (empty without one); it outranks application.conf and the launcher's defaults.
    */
  def config(args: Seq[String]): Config = {
    val file = args.headOption.map { path =>
      val f = new File(path)
      require(f.isFile, s"config file $path does not exist")
      ConfigFactory.parseFile(f)
    }
    file.getOrElse(ConfigFactory.empty())
  }

  /** The gateway node's whole config: the file (`overrides`), then `application` (application.conf or -Dconfig.file),
    * then the launcher's defaults with the environment variables they name, then the cluster settings and references.
    */
  def nodeConfig(overrides: Config, application: => Config = ConfigFactory.defaultApplication()): Config =
    MiddlewareCluster.config(MiddlewareCluster.GatewayRole, overrides, defaults, application)

  /** The command line: an optional config file, and a recording to replay instead of the sockets. */
  final case class Arguments(configFile: Option[String], replay: Option[Replay])

  /** `[config-file] [--replay FILE-OR-DIRECTORY [--speed X]]`, in any order. A replay runs no simulated robot and no
    * simulated GameController: the recording's robots and game are what the gateway sees.
    */
  def arguments(args: Seq[String]): Arguments = {
    def loop(rest: List[String], got: Arguments, speed: Option[Double]): Arguments = rest match {
      case "--replay" :: path :: more => loop(more, got.copy(replay = Some(Replay.of(Paths.get(path)))), speed)
      case "--speed" :: x :: more =>
        val v = x.toDoubleOption.getOrElse(throw new IllegalArgumentException(s"--speed $x is not a number"))
        loop(more, got, Some(v))
      case ("--replay" | "--speed") :: Nil        => throw new IllegalArgumentException(s"${rest.head} needs a value")
      case flag :: _ if flag.startsWith("--")     => throw new IllegalArgumentException(s"unknown option $flag")
      case file :: more if got.configFile.isEmpty => loop(more, got.copy(configFile = Some(file)), speed)
      case extra :: _ => throw new IllegalArgumentException(s"one config file only (also got $extra)")
      case Nil =>
        require(speed.isEmpty || got.replay.isDefined, "--speed goes with --replay")
        got.copy(replay = got.replay.map(r => speed.fold(r)(v => r.copy(speed = v))))
    }
    loop(args.toList, Arguments(None, None), None)
  }

  /** What a replay changes in the launcher's config: no simulated robots, no simulated GameController. */
  private val ReplayOverrides: Config =
    ConfigFactory.parseString("apps.launcher { simulated-robots = 0, game-controller = off }")

  def main(args: Array[String]): Unit = {
    // Logback is set up before the actor systems' threads log at once; otherwise SLF4J queues their first lines and
    // prints a warning about replaying them on every start.
    org.slf4j.LoggerFactory.getILoggerFactory
    val (parsed, overrides) =
      try {
        val a = arguments(args.toSeq)
        val c = config(a.configFile.toSeq)
        // Simulated robots on this host answer the GameController from it, and a GameController refuses a host that
        // ever sent a status message as a monitor: the two do not go together.
        val resolved = c.withFallback(ConfigFactory.load()).resolve()
        require(
          !(resolved.getBoolean("naogateway.game-controller.monitor.enabled") && a.replay.isEmpty &&
            resolved.getInt("apps.launcher.simulated-robots") > 0),
          "game-controller.monitor: the simulated robots on this host would answer the GameController from it, which " +
            "then refuses this host as a monitor; set apps.launcher.simulated-robots = 0 (real robots) or turn the " +
            "monitor off"
        )
        (a, if (a.replay.isDefined) ReplayOverrides.withFallback(c) else c)
      } catch {
        // A wrong file name or a typo in the file is the operator's to fix: say what and where, without a stack trace.
        case e @ (_: IllegalArgumentException | _: com.typesafe.config.ConfigException) =>
          System.err.println(s"naogateway: ${e.getMessage.stripPrefix("requirement failed: ")}")
          System.err.println(
            "usage: naogateway [config-file] [--replay FILE-OR-DIRECTORY [--speed X]]   (no file: the demo with " +
              "simulated robots)")
          sys.exit(2)
      }
    val nodeConfig = checked(overrides, code => sys.exit(code))
    val gatewayNode =
      try MiddlewareCluster.start(Root(parsed.replay, exitWhenStopped), nodeConfig)
      catch {
        // Another program took a port between the check and the bind: the same one line, not Akka's stack trace.
        case NonFatal(e) if bindFailure(e) =>
          Preflight.portProblems(Preflight.ports(nodeConfig)).foreach(l => System.err.println(s"naogateway: $l"))
          System.err.println(s"naogateway: cannot bind a port: ${rootCause(e).getMessage}")
          sys.exit(ExitPortInUse)
      }
    // Ctrl-C (or a TERM) runs the JVM shutdown hooks: both actor systems leave and stop within the phase timeouts.
    CoordinatedShutdown(gatewayNode.classicSystem).addJvmShutdownHook(println("naogateway stopped"))
  }

  /** The exit codes of a launcher that could not start: a config problem, and a port it cannot have. */
  val ExitConfig = 2
  val ExitPortInUse = 3

  /** The exit code of a launcher whose gateway or middleware stopped while it ran. */
  val ExitPartStopped = 4

  /** What the launcher does when its gateway or middleware stops: says so on the terminal and exits
    * [[ExitPartStopped]], from a thread of its own (System.exit waits for the shutdown hooks, which wait for the
    * actors).
    */
  private def exitWhenStopped(part: String): Unit = {
    System.err.println(s"naogateway: the $part stopped; exiting")
    new Thread(() => sys.exit(ExitPartStopped), "naogateway-exit").start()
  }

  /** The gateway node's config once it passed the checks of [[Preflight]]: a config problem is one line naming the key
    * (exit [[ExitConfig]]); a port held by another program one line each, naming the port, its use and the setting that
    * moves it (exit [[ExitPortInUse]]; a warning for the GameController's port, without which the gateway runs with
    * game state unknown); the demo's robots on a machine without their loopback addresses one line saying what to do
    * (exit [[ExitConfig]]). Keys no reference knows are warned about. Lines go to `err`.
    */
  def checked(overrides: Config, exit: Int => Nothing, err: String => Unit = System.err.println,
      application: => Config = ConfigFactory.defaultApplication(),
      probe: Preflight.PortUse => Preflight.Probe = Preflight.probe,
      loopback: java.net.InetAddress => Boolean = Preflight.loopbackBindable): Config = {
    val c =
      try { val c = nodeConfig(overrides, application); Preflight.validate(c); c }
      catch {
        case NonFatal(e) if Preflight.problem(e).isDefined =>
          err(s"naogateway: ${Preflight.problem(e).get}")
          exit(ExitConfig)
      }
    Preflight.unknownKeys(c, Preflight.knownKeys).foreach(k =>
      err(s"naogateway: warning: config key $k is not a setting (a typo?); it is ignored"))
    Preflight.doorWarnings(c).foreach(l => err(s"naogateway: warning: $l"))
    val simulated = c.getInt("apps.launcher.simulated-robots")
    Preflight.missingLoopback(simulated, loopback).foreach { line =>
      err(s"naogateway: $line")
      exit(ExitConfig)
    }
    val (essential, optional) = Preflight.ports(c).partition(_.essential)
    Preflight.portProblems(optional, probe).foreach(l => err(s"naogateway: warning: $l"))
    val ports = Preflight.portProblems(essential, probe)
    if (ports.nonEmpty) {
      ports.foreach(l => err(s"naogateway: $l"))
      exit(ExitPortInUse)
    }
    c
  }

  private def rootCause(e: Throwable): Throwable = Option(e.getCause).filter(_ ne e).fold(e)(rootCause)

  private def bindFailure(e: Throwable): Boolean =
    rootCause(e).isInstanceOf[java.net.BindException] || e.isInstanceOf[akka.remote.RemoteTransportException]

  /** The demo's simulated robots introduce themselves with their keep-alives like strangers would: the discovery cap is
    * raised to their number when it is smaller (a demo on loopback, not a shared WiFi).
    */
  private def demoDiscovery(settings: GatewaySettings, simulated: Int): GatewaySettings =
    if (simulated <= settings.discovery.maxRobots) settings
    else settings.copy(discovery = settings.discovery.copy(maxRobots = simulated))

  /** How long apps wait for the gateway's view to answer a question (each asks the robot actors in turn). */
  val ViewTimeout: FiniteDuration = 3.seconds

  /** What the root of the gateway node accepts. */
  sealed trait Command
  private final case class Addresses(addresses: GatewayAddresses) extends Command
  // The simulated robots, and the gateway's GameController port the demo's GameController sends to beside them.
  private final case class FleetStarted(
      result: scala.util.Try[naogateway.sim.FleetHandle], gameController: Option[InetSocketAddress])
      extends Command
  private final case class PartStopped(part: String) extends Command

  /** The gateway node's root: gateway (on its sockets, or replaying), middleware, simulated robots, status view, app
    * node. It watches the gateway and the middleware: when either stops (it failed, or lost its socket) outside a
    * shutdown, nothing the node offers works any more, so the root calls `stopped` with its name ("gateway",
    * "middleware") and stops, and the actor system with it. `makeMiddleware` makes the middleware in front of the
    * gateway.
    */
  def Root(
      replay: Option[Replay] = None,
      stopped: String => Unit = _ => (),
      makeMiddleware: ActorRef[GatewayAccess.Command] => Behavior[RobotMiddleware.Command] = configuredMiddleware
  ): Behavior[Command] = Behaviors.setup { context =>
    val config = context.system.settings.config
    val launcher = settings(config.getConfig("apps.launcher"))
    val gateway =
      context.spawn(Gateway(demoDiscovery(GatewaySettings(context.system), launcher.simulatedRobots), replay),
        "gateway")
    val middleware = context.spawn(makeMiddleware(gateway), "middleware",
      RobotMiddleware.dispatcher(MiddlewareSettings(context.system)))
    context.watchWith(gateway, PartStopped("gateway"))
    context.watchWith(middleware, PartStopped("middleware"))
    // The doors open by name, or (auto) only beside simulated robots.
    val realRobots = Doors.realRobots(config)
    apps.zeromq.ZeroMqEndpoint.spawnIfEnabled(context, middleware, realRobots)
    apps.datagram.DatagramDoor.spawnIfEnabled(context, middleware, realRobots)
    /* The bus bridge (docs/protocol.md 6.9), when enabled: an app at the middleware holds the leases while a tool is
     * on. */
    val busBridge = naogateway.gateway.BusBridgeSettings.fromConfig(config.getConfig("naogateway"))
    if (busBridge.enabled) {
      val leases = context.spawn(robotmiddleware.BusBridgeLeases(middleware), "bus-bridge-leases")
      context.spawn(naogateway.gateway.BusBridgeServer(gateway, busBridge, Some(leases)), "bus-bridge")
    }
    val view = GatewayReadView(gateway, ViewTimeout)(context.system)
    val doctor = () =>
      Doctor.gather(gateway, config)(context.system).map(f => Doctor.findings(f) :+ Doctor.clusterFinding(config))(
        context.executionContext)
    // The demo's robots, once started: `robotctl battery <id> swap` reaches them, and only them.
    val fleet = new java.util.concurrent.atomic.AtomicReference(Option.empty[naogateway.sim.FleetHandle])
    val control = apps.control.ControlServer.GatewaySide(view, doctor, batterySwap(fleet.get, _))
    apps.control.ControlServer.spawnIfEnabled(context, middleware, Some(control))
    // The web view (docs/web.md), when enabled: its address goes on the status view's first line.
    val webAddress = new java.util.concurrent.atomic.AtomicReference(Vector.empty[String])
    val gatewaySettings = GatewaySettings(context.system)
    val web =
      apps.web.WebServer.GatewaySide(view, gatewaySettings.competition, id => gatewaySettings.signingOf(id).name)
    apps.web.WebServer.spawnIfEnabled(context, web, middleware, realRobots,
      bound =>
        webAddress.set(bound.map(a => apps.web.WebServer.describe(a, apps.web.WebSettings(context.system))).toVector))
    context.spawn(StatusPrinter.fromConfig(view, config.getConfig("apps.launcher"), () => webAddress.get,
        MiddlewareSettings(context.system).servoLimits), "status")
    gateway ! GatewayAccess.GetAddresses(context.messageAdapter(Addresses.apply))

    Behaviors.receiveMessage {
      case Addresses(addresses) =>
        if (launcher.simulatedRobots > 0) {
          val robots = addresses.robots
          val target =
            if (robots.getAddress.isAnyLocalAddress) new InetSocketAddress("127.0.0.1", robots.getPort) else robots
          // With a team key the simulated robots sign, each with its own robot key, as robots built with
          // `robotctl keys` do (docs/protocol.md 6.7).
          val teamKey = gatewaySettings.signingKey
          context.pipeToSelf(Fleet.start(
              context.system,
              FleetSettings(
                target,
                (1 to launcher.simulatedRobots).toVector,
                faithfulLink = launcher.simulatedRobots <= 20,
                // With the bus bridge on, the robots take part in the secure stream that carries it.
                customize = s => {
                  // The demo's GameController is the simulated one on this host: a robot heeds no other's packets.
                  val signed = s.copy(firmware = s.firmware.copy(signingKey = teamKey,
                    gameControllerSource = Some(InetAddress.getLoopbackAddress)))
                  if (busBridge.enabled) signed.withStream(gatewaySettings.stream) else signed
                }
              )
            ))(FleetStarted(_, addresses.gameController))
        }
        if (launcher.ballFollowerRobot > 0) startBallFollower(context.system, launcher.ballFollowerRobot)
        Behaviors.same
      case FleetStarted(Success(started), gameController) =>
        context.log.info("Started {} simulated robots", started.robots.size)
        fleet.set(Some(started))
        // The GameController starts with the robots: its rounds reach them as a broadcast would (docs/protocol.md 6.9).
        startGameController(context, gameController, started.robots.map(_._2))
        Behaviors.same
      case FleetStarted(Failure(e), _) =>
        context.log.error("Simulated robots did not start", e)
        Behaviors.same
      case PartStopped(_) if CoordinatedShutdown(context.system).shutdownReason().isDefined =>
        Behaviors.same // the node is shutting down: its parts stop as they should
      case PartStopped(part) =>
        context.log.error("The {} stopped: the gateway node stops", part)
        stopped(part)
        Behaviors.stopped
    }
  }

  /** `robotctl battery <id> swap`: a simulated robot of `fleet` gets a full battery at once, as a team swaps one; any
    * other robot is real, and refused.
    */
  private[launcher] def batterySwap(
      fleet: Option[naogateway.sim.FleetHandle], robotId: Int): scala.concurrent.Future[String] =
    fleet.flatMap(_.robot(robotId)) match {
      case Some(robot) =>
        val full = naogateway.sim.FirmwareSettings(robotId).fullBattery
        robot ! naogateway.sim.SimulatedRobot.SetBattery(full)
        scala.concurrent.Future.successful(
          f"robot $robotId: battery swapped for a full one ($full%.2f V); a hold for low battery ends " +
            "once its keep-alives read it")
      case None => apps.control.ControlServer.GatewaySide.noSimulatedRobots(robotId)
    }

  /** The middleware with the settings of the node's config. */
  private def configuredMiddleware(gateway: ActorRef[GatewayAccess.Command]): Behavior[RobotMiddleware.Command] =
    Behaviors.setup(context => RobotMiddleware(gateway, MiddlewareSettings(context.system)))

  /** The demo's simulated GameController (`apps.launcher.game-controller`, only with simulated robots), sending to the
    * gateway's GameController port `gameController` (on loopback when the gateway listens on every address) and to each
    * simulated robot at `robots`, as a real GameController's broadcast reaches the gateway and the robots alike: the
    * robots learn the game state, and close their bus bridge while the game runs (docs/protocol.md 6.9).
    */
  private def startGameController(context: akka.actor.typed.scaladsl.ActorContext[Command],
      gameController: Option[InetSocketAddress], robots: Vector[InetSocketAddress]): Unit = {
    val c = context.system.settings.config.getConfig("apps.launcher")
    // Only beside simulated robots: against real robots a simulated game would open and close the competition gate.
    for (gc <- gameController if c.getBoolean("game-controller") && c.getInt("simulated-robots") > 0) {
      val target =
        if (gc.getAddress.isAnyLocalAddress) naogateway.sim.SimulatedGameController.loopback(gc.getPort) else gc
      val number = c.getInt("game-controller-version")
      val version = naogateway.wire.gamecontroller.GameControlVersion.all.find(_.number == number).getOrElse(
        throw new IllegalArgumentException(
          s"apps.launcher.game-controller-version $number: the simulation plays 20, 19, 12, 8 or 7"))
      context.spawn(naogateway.sim.SimulatedGameController(naogateway.sim.SimulatedGameControllerSettings(target,
            version = version, robots = robots)), "game-controller")
    }
  }

  /** The ball follower runs in an actor system of its own, a cluster node with role "app", as every app does. */
  private def startBallFollower(gatewayNode: ActorSystem[_], robotId: Int): Unit = {
    val appNode = MiddlewareCluster.start(
      Behaviors.setup[BallFollowerNode] { context =>
        context.pipeToSelf(RobotClient(context.system, "ball-follower", priority = 1))(BallFollowerNode.apply)
        Behaviors.receiveMessage {
          case BallFollowerNode(Success(robot)) =>
            context.spawn(BallFollower(robot, robotId), "ball-follower")
            Behaviors.same
          case BallFollowerNode(Failure(e)) =>
            // On a loaded machine the app node may join after RobotClient's search gave up: it searches again.
            context.log.warn("Ball follower found no middleware yet ({}); searching again in {}", e.getMessage,
              BallFollowerRetry)
            context.pipeToSelf(akka.pattern.after(BallFollowerRetry)(
                RobotClient(context.system, "ball-follower", priority = 1))(context.system))(BallFollowerNode.apply)
            Behaviors.same
        }
      },
      MiddlewareCluster.AppRole,
      appNodeConfig(gatewayNode.settings.config)
    )
    // The app node lives and dies with the gateway node.
    CoordinatedShutdown(gatewayNode.classicSystem).addTask(CoordinatedShutdown.PhaseBeforeServiceUnbind, "stop-apps") {
      () =>
        appNode.terminate()
        appNode.whenTerminated
    }
  }

  /** What the demo's app node takes over from the gateway node's config: where the cluster is, the dispatchers' sizes
    * and which of them runs Artery, and what makes a Ctrl-C quick (the shutdown's phase timeouts, the leader's pace,
    * Artery's flush at shutdown); and its own scheduler's pace ([[AppNodeScheduler]]).
    */
  def appNodeConfig(gatewayNode: Config): Config =
    Seq(
      "robotmiddleware.cluster",
      "akka.actor.default-dispatcher",
      "akka.actor.internal-dispatcher",
      "akka.remote.default-remote-dispatcher",
      "akka.remote.use-dispatcher",
      "akka.remote.artery.advanced.use-dispatcher",
      "akka.coordinated-shutdown",
      "akka.cluster.leader-actions-interval",
      "akka.remote.artery.advanced.shutdown-flush-timeout"
    )
      .foldLeft(AppNodeScheduler) { (c, path) =>
        c.withValue(path, gatewayNode.getValue(path))
      }

  /** The app node's scheduler ticks every 50 ms rather than Akka's 10 ms: its timers (the cluster's, second-long; the
    * ball follower's retries; ask timeouts) need no finer grain, and each tick wakes its thread whether a timer is due
    * or not. The cluster's periodic tasks share it (a cluster tick shorter than the default's would start a scheduler
    * of its own).
    */
  private val AppNodeScheduler: Config =
    ConfigFactory.parseString("akka.scheduler.tick-duration = 50ms\nakka.cluster.scheduler.tick-duration = 50ms")

  private final case class BallFollowerNode(robot: scala.util.Try[robotmiddleware.RobotInterface])

  /** The pause before the ball follower searches for the middleware again. */
  private val BallFollowerRetry: FiniteDuration = 5.seconds
}
