package naogateway

import java.net.{InetAddress, InetSocketAddress}
import java.util.concurrent.ConcurrentHashMap
import java.util.concurrent.atomic.{AtomicLong, AtomicReference}

import akka.actor.typed.scaladsl.{ActorContext, Behaviors, StashBuffer}
import akka.actor.typed.{ActorRef, Behavior, DispatcherSelector, PostStop}
import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.reflect.ClassTag

import org.slf4j.LoggerFactory

import naogateway.link.{Backlog, DatagramWriter, Replay, ReplayLink, RobotLink, RobotPort, UdpLink}
import naogateway.proto.RecordedPort
import naogateway.recording.{Decision, Recording, RecordingStats, RobotClockEstimates}
import naogateway.wire._
import naogateway.wire.gamecontroller.{GameControlData, GameControlVersion, GameControllerCodec}

/** The robot side of the middleware: the robots' UDP port, the robot registry, the GameController and the relay. */
object Gateway {

  /** What the gateway accepts. */
  sealed trait Command

  /**
   * The read-only view of the gateway: questions that change nothing. Operator tools (the status view, the control
   * port) hold an `ActorRef[Gateway.Query]`, so they can look but never reach a robot past the middleware.
   */
  sealed trait Query extends Command

  /** Answers with the bound addresses (the real ports when 0 was configured). */
  final case class GetAddresses(replyTo: ActorRef[Addresses]) extends Query

  /** Answers with every known robot's snapshot, asked of the robot actors (`snapshot-timeout` for each). */
  final case class GetRobots(replyTo: ActorRef[Vector[RobotSnapshot]]) extends Query

  /** Answers with the robot actor of `robotId`, if the robot is known. */
  final case class GetRobot(robotId: Int, replyTo: ActorRef[Option[ActorRef[RobotActor.Command]]]) extends Command

  /** Answers with every known robot's link figures, asked of the robot actors (`snapshot-timeout` for each). */
  final case class GetLinkStats(replyTo: ActorRef[RobotLinks]) extends Query

  /** The link figures of every robot whose actor answered `GetLinkStats` in time, by robot id. */
  final case class RobotLinks(links: Vector[LinkStats])

  /** Lets robot `robotId` be re-bound to the IP address its next datagram comes from (a robot that moved host). */
  final case class AllowRebind(robotId: Int) extends Command

  /** Sends every `GatewayEvent` to `subscriber` until it stops (robot events come straight from the robot actors). */
  final case class Subscribe(subscriber: ActorRef[GatewayEvent]) extends Command

  /** Stops sending events to `subscriber`. */
  final case class Unsubscribe(subscriber: ActorRef[GatewayEvent]) extends Command

  /** Answers with the gateway's own figures. */
  final case class GetStats(replyTo: ActorRef[GatewayStats]) extends Query

  /** Answers with the team traffic figures of the outbox. */
  final case class GetTraffic(replyTo: ActorRef[Outbox.TrafficStats]) extends Query

  /** Answers with the latest GameController packet, if any arrived. */
  final case class GetGameState(replyTo: ActorRef[Option[GameControlData]]) extends Query

  /** Answers with where game state comes from: the trusted sources, the last sender and the packets ignored. */
  final case class GetGameSource(replyTo: ActorRef[GameSource]) extends Query

  private final case class GameControllerEvent(event: UdpLink.Event) extends Command
  private final case class TeamMessageEvent(event: UdpLink.Event) extends Command
  private final case class MonitorStatusEvent(event: UdpLink.Event) extends Command
  private final case class Unrouted(frame: Routing.ToGateway) extends Command
  private final case class SubscriberGone(subscriber: ActorRef[GatewayEvent]) extends Command
  private final case class RobotStopped(robotId: Int, actor: ActorRef[RobotActor.Command]) extends Command
  private final case class RobotWantsSubscribers(request: RobotActor.SubscribersWanted) extends Command

  /**
   * Where the game state comes from, for the status view and robotctl.
   *
   * @param trusted the configured GameController addresses or subnets, in words ("any source" when none is)
   * @param lastFrom the sender of the last control packet that counted
   * @param untrusted control packets ignored because they came from elsewhere
   * @param budget the team's message budget in one line, when the gateway counts it ([[MessageBudget.describe]])
   * @param warnings what needs the team's attention: a second GameController, the message budget
   * @param trueStateAgeMillis in the monitor role: how old the last true game state (`RGTD`) is; `None` before the first
   * @param forwarded in the monitor role: the robots' status messages the GameController forwarded, by team and player
   */
  final case class GameSource(trusted: String, lastFrom: Option[InetSocketAddress], untrusted: Long,
      budget: Option[String] = None, warnings: Vector[String] = Vector.empty, trueStateAgeMillis: Option[Long] = None,
      forwarded: Vector[ForwardedStatus] = Vector.empty) {

    /** One line: "game state from 10.0.0.5:3838 (trusted: 10.0.0.0/24), 3 packets from elsewhere ignored". */
    def describe: String =
      s"game state from ${lastFrom.fold("nowhere yet")(a => s"${a.getAddress.getHostAddress}:${a.getPort}")} (trusted: $trusted)" +
        (if (untrusted > 0) s", $untrusted packet(s) from elsewhere ignored" else "")
  }

  /** Where the gateway listens. */
  final case class Addresses(robots: InetSocketAddress, gameController: Option[InetSocketAddress])

  /**
   * The gateway's own figures: datagrams seen, relayed, refused by kind (a closed set, [[Rejection]]) and by source
   * address (at most [[RejectionAddresses]] of them, the rest under "other addresses").
   */
  final case class GatewayStats(datagramsIn: Long, relayed: Long, gameControllerPackets: Long, rejected: Map[String, Long], robots: Int,
      rejectedBySource: Map[String, Long] = Map.empty, recording: RecordingStats = Recording.Off.stats,
      replay: Option[Replay.Progress] = None)

  /** Received datagrams the port's reader counts before it tells the outbox (one message, not one per datagram). */
  val InboundBatch: Int = 64

  /** Source addresses whose refusals are counted one by one; the rest are counted together (`other addresses`). */
  val RejectionAddresses: Int = 64

  /** Where the robot actors, their children and the outbox run (`naogateway.dispatcher`). */
  val RobotDispatcher: DispatcherSelector = DispatcherSelector.fromConfig("naogateway.dispatcher")

  /**
   * A datagram robot as the port's reader reaches it: its actor, the backlog of what the reader handed it, and for a
   * robot that must sign, the check every frame passes before it is handed on.
   */
  private final case class Inlet(actor: ActorRef[RobotActor.Command], backlog: Backlog, signatures: Option[SignatureCheck])

  /**
    * A known robot: `address` is where it receives (its IP at its receive port), and its IP is who it is; with
    * `signatures`, its frames count only when signed (the IP alone does not identify it then). A `discovered` one was
    * introduced by its keep-alive: it counts against `discovery.max-robots` and may be forgotten.
    */
  private final case class Entry(actor: ActorRef[RobotActor.Command], address: InetSocketAddress, zeromq: Boolean,
      backlog: Backlog, signatures: Option[SignatureCheck] = None, discovered: Boolean = false)

  /**
   * The gateway with `configured` settings, on its sockets; or, with `replay`, fed from a recording instead: no socket
   * is opened, nothing is sent anywhere, nothing is recorded.
   */
  def apply(configured: GatewaySettings, replay: Option[Replay] = None): Behavior[Command] =
    Behaviors.setup { context =>
      // A replay reaches no robot: ZeroMQ robots, which would be called over their own sockets, are left out.
      val settings = if (replay.isEmpty) configured else configured.copy(zeromq = configured.zeromq.copy(robots = Vector.empty))
      Behaviors.withStash(1024) { stash =>
        val bind = new InetSocketAddress(settings.bindAddress, settings.robotPort)
        val port: RobotLink = replay match {
          case Some(r) =>
            context.log.info("Gateway replaying {} at {}x: nothing is sent", r.files.mkString(", "), r.speed)
            new ReplayLink(r, s"${context.system.name}-replay")
          case None =>
            val p =
              try RobotPort.open(bind, ReceiveBufferBytes, s"${context.system.name}-robot-port")
              catch { case e: java.io.IOException => throw new IllegalStateException(s"gateway cannot listen for robots on $bind: $e", e) }
            context.log.info("Gateway listening for robots on {}", p.localAddress)
            p
        }
        val clocks = new RobotClockEstimates
        val recording =
          if (replay.isDefined) Recording.Off else Recording(settings.recording, s"${context.system.name}-recorder", clocks)
        val routes = new AtomicReference[Routing.Table[Inlet]](Routing.Table.empty)
        // One signer for the gateway's life: its timestamps keep growing across restarts of the outbox.
        val signer = settings.signingKey.filter(_ => settings.robots.exists(_.signing == RobotSigning.Required)).map(new FrameSigner(_))
        val outbox = context.spawn(
          Behaviors.supervise(Outbox(recorded(port, recording, RecordedPort.ROBOT_PORT, port.localAddress, routes), settings.budget,
            settings.competition, signer, recording))
            .onFailure(settings.supervision.outbox.strategy),
          "outbox",
          RobotDispatcher
        )
        val logic = new GatewayLogic(settings, context, stash, port, outbox, recording, routes, clocks)
        logic.start()
        if (settings.gameControllerEnabled && settings.teamMessages.enabled && replay.isEmpty) {
          // Akka keeps one message adapter per message class, and the GameController link's events are of the same
          // class: a child of its own marks the team port's events instead.
          val self = context.self
          val teamEvents = context.spawn(Behaviors.receiveMessage[UdpLink.Event] { e =>
            self ! TeamMessageEvent(e)
            Behaviors.same
          }, "team-message-events")
          context.spawn(
            UdpLink(new InetSocketAddress(settings.gameControllerBindAddress, settings.teamMessages.port), teamEvents,
              UdpLink.Options(reuseAddress = true, broadcast = true, maxDatagramsPerSecond = settings.teamMessages.maxDatagramsPerSecond)),
            "team-message-link"
          )
        }
        if (settings.gameControllerEnabled && replay.isEmpty) {
          context.spawn(
            UdpLink(new InetSocketAddress(settings.gameControllerBindAddress, settings.gameControllerPort),
              context.messageAdapter(GameControllerEvent.apply),
              UdpLink.Options(reuseAddress = settings.gameControllerReuseAddress, broadcast = true,
                maxDatagramsPerSecond = settings.gameControllerMaxDatagramsPerSecond)),
            "game-controller-link"
          )
          logic.bindingGameController
        } else stash.unstashAll(logic.running(Addresses(port.localAddress, None)))
      }
    }

  /** `link`, with every datagram it takes recorded as sent from `local` on `port` (`link` itself when not recording). */
  private def recorded(link: DatagramWriter, recording: Recording, port: RecordedPort, local: InetSocketAddress,
      routes: AtomicReference[Routing.Table[Inlet]]): DatagramWriter =
    if (!recording.enabled) link
    else
      new DatagramWriter {
        def send(bytes: Array[Byte], to: InetSocketAddress): Boolean = {
          val sent = link.send(bytes, to)
          if (sent) recording.datagram(port, received = false, local, to, bytes, routes.get.byAddress.get(to.getAddress).fold(-1)(_.robotId))
          sent
        }
      }

  /**
   * Hands the gateway's events to the recording; a keep-alive (on the recording's status channels already) only
   * brings the robot's clock estimate, with which the recorder dates the robot's Status.
   */
  private def recordingEvents(recording: Recording, clocks: RobotClockEstimates): Behavior[GatewayEvent] = Behaviors.receiveMessage {
    case RobotStatusUpdated(snapshot) =>
      clocks.update(snapshot.robotId, snapshot.clock)
      Behaviors.same
    case event =>
      recording.decision(Decision.Published(event))
      Behaviors.same
  }

  /** The kernel receive buffer of the robot port: a burst of a few thousand datagrams waits there, not dropped. */
  private val ReceiveBufferBytes = 4 * 1024 * 1024

  /**
   * Refused datagrams by kind and by source address, counted by the port's reader and the gateway alike (so the maps
   * are concurrent). Both are bounded: the kinds are a closed set, and addresses beyond [[RejectionAddresses]] share
   * one counter. A warning names the kind only, at its 1st, 10th, 100th … refusal; the sender and its values go to
   * the debug log, so nothing a sender chooses can make the log grow faster.
   */
  private final class Rejections {
    private val counts = new ConcurrentHashMap[Rejection, AtomicLong]()
    private val bySource = new ConcurrentHashMap[java.net.InetAddress, AtomicLong]()
    private val otherSources = new AtomicLong
    private val log = LoggerFactory.getLogger("naogateway.Gateway")

    def count(kind: Rejection, from: InetSocketAddress, detail: => String = "", times: Long = 1L): Unit = {
      val n = counts.computeIfAbsent(kind, _ => new AtomicLong).addAndGet(times)
      val address = from.getAddress
      val known = bySource.get(address)
      if (known != null) known.addAndGet(times)
      else if (bySource.size < RejectionAddresses) bySource.computeIfAbsent(address, _ => new AtomicLong).addAndGet(times)
      else otherSources.addAndGet(times)
      if (RateLimitedLog.dueBetween(n - times, n)) log.warn("Refused datagram: {} ({} so far)", kind.name, n)
      if (log.isDebugEnabled) log.debug("Refused datagram from {}: {} {}", from, kind.name, detail)
    }

    def snapshot: Map[String, Long] = counts.asScala.iterator.map { case (k, v) => k.name -> v.get }.toMap

    def sources: Map[String, Long] = {
      val each = bySource.asScala.iterator.map { case (a, v) => a.getHostAddress -> v.get }.toMap
      if (otherSources.get > 0) each.updated("other addresses", otherSources.get) else each
    }
  }

  /**
   * The robot port's reader side of the gateway: runs on the reader thread, routes each datagram with the table the
   * gateway last published, and hands the robot actors (or the gateway) their messages directly.
   */
  private final class PortReader(
      settings: GatewaySettings,
      port: RobotLink,
      gateway: ActorRef[Command],
      gatewayBacklog: Backlog,
      outbox: ActorRef[Outbox.Command],
      rejections: Rejections,
      recording: Recording,
      val routes: AtomicReference[Routing.Table[Inlet]]
  ) extends RobotPort.Handler {
    // Written by the reader thread only; read by the gateway for its figures.
    @volatile var datagramsIn, relayed = 0L
    // What the outbox has not been told yet: told in one message per InboundBatch datagrams or when the port is quiet.
    private var inboundDatagrams, inboundBytes = 0
    private val relayLink = recorded(port, recording, RecordedPort.FU_REMOTE_RELAY, port.localAddress, routes)

    def received(bytes: Array[Byte], from: InetSocketAddress): Unit = {
      datagramsIn += 1
      val table = routes.get
      if (recording.enabled) {
        val robotId = table.byAddress.get(from.getAddress).fold(-1)(_.robotId)
        recording.datagram(RecordedPort.ROBOT_PORT, received = true, from, port.localAddress, bytes, robotId)
      }
      settings.relay.foreach { relay =>
        if (relayLink.send(bytes, relay)) relayed += 1
      }
      inboundDatagrams += 1
      inboundBytes += bytes.length
      if (inboundDatagrams >= InboundBatch) caughtUp()
      Routing.decide(table, bytes, from) match {
        case Routing.ToRobot(route, header, contents, size) =>
          // A robot that must sign: nothing acts on its frame before the signature and the replay window pass.
          route.target.signatures.map(_.check(bytes, header)) match {
            case Some(Left(kind)) =>
              rejections.count(kind, from)
              if (route.target.backlog.tryAdd()) route.target.actor ! RobotActor.DatagramRejected(kind)
            case _ => deliver(route, RobotActor.FrameReceived(contents, header.form, size), from)
          }
        case Routing.SegmentToRobot(route, segment) =>
          deliver(route, RobotActor.SegmentReceived(segment), from)
        case unrouted: Routing.ToGateway =>
          if (gatewayBacklog.tryAdd()) gateway ! Unrouted(unrouted) else rejections.count(Rejection.GatewayBusy, from)
        case Routing.Refused(kind, detail, route) =>
          rejections.count(kind, from, detail)
          route.foreach(r => if (r.target.backlog.tryAdd()) r.target.actor ! RobotActor.DatagramRejected(kind))
      }
    }

    private def deliver(route: Routing.Route[Inlet], message: RobotActor.Command, from: InetSocketAddress): Unit =
      if (route.target.backlog.tryAdd()) route.target.actor ! message else rejections.count(Rejection.RobotBusy, from)

    def caughtUp(): Unit =
      if (inboundDatagrams > 0) {
        outbox ! Outbox.Inbound(inboundDatagrams, inboundBytes)
        inboundDatagrams = 0
        inboundBytes = 0
      }

    def gameControllerReceived(bytes: Array[Byte], from: InetSocketAddress): Unit =
      gateway ! GameControllerEvent(UdpLink.Received(bytes, from))
  }

  private final class GatewayLogic(
      settings: GatewaySettings,
      context: ActorContext[Command],
      stash: StashBuffer[Command],
      port: RobotLink,
      outbox: ActorRef[Outbox.Command],
      recording: Recording,
      routes: AtomicReference[Routing.Table[Inlet]],
      clocks: RobotClockEstimates
  ) {
    private val subscriptionRequests = context.messageAdapter[RobotActor.SubscribersWanted](RobotWantsSubscribers.apply)
    private val rejections = new Rejections
    private val gatewayBacklog = new Backlog(settings.gatewayBacklog)
    private val reader = new PortReader(settings, port, context.self, gatewayBacklog, outbox, rejections, recording, routes)
    private var gameControllerAddress: Option[InetSocketAddress] = None
    private var byId = Map.empty[Int, Entry]
    // Keyed by IP alone: a robot's source port changes when its module reconnects, its IP does not.
    private var byAddress = Map.empty[InetAddress, Int]
    private var subscribers: Set[ActorRef[GatewayEvent]] =
      // On the robot actors' own thread: every keep-alive's status event comes here, and a hand-over to another thread per
      // keep-alive would cost more than the update itself.
      if (recording.enabled) Set(context.spawn(recordingEvents(recording, clocks), "recording-events", RobotDispatcher)) else Set.empty
    private var rebindable = Set.empty[Int]
    private var gcPackets = 0L
    private var game: Option[GameControlData] = None
    private var gameFrom: Option[InetSocketAddress] = None
    private var gameUntrusted = 0L

    private var lastUnreadable: Option[(Long, String)] = None
    private var sources = GameControllerSources()
    private var trueStateAt: Option[Long] = None
    private var forwarded = ForwardedStatuses()

    /**
     * The monitor role: the request for the true state, from the GameController socket, now and every request-interval
     * (a child owns the timer); the forwarded status messages on a socket of their own.
     */
    private def startMonitor(gcLink: ActorRef[UdpLink.Command], m: MonitorSettings): Unit = {
      context.log.info("Gateway monitoring the GameController at {}: asking for the true game state every {}", m.gameController,
        m.requestInterval)
      context.spawn(Behaviors.withTimers[String] { timers =>
        gcLink ! UdpLink.Send(GameControllerCodec.monitorRequest, m.gameController)
        timers.startTimerWithFixedDelay("request", m.requestInterval)
        Behaviors.receiveMessage { _ =>
          gcLink ! UdpLink.Send(GameControllerCodec.monitorRequest, m.gameController)
          Behaviors.same
        }
      }, "monitor-requests")
      val self = context.self
      val statusEvents = context.spawn(Behaviors.receiveMessage[UdpLink.Event] { e =>
        self ! MonitorStatusEvent(e)
        Behaviors.same
      }, "monitor-status-events")
      context.spawn(UdpLink(new InetSocketAddress(settings.gameControllerBindAddress, m.statusPort), statusEvents,
        UdpLink.Options(reuseAddress = true, maxDatagramsPerSecond = settings.gameControllerMaxDatagramsPerSecond)), "monitor-status-link")
    }

    /** Whether the monitor role's true state is fresh enough that the broadcast one is not used. */
    private def trueStateFresh(now: Long): Boolean =
      settings.monitor.exists(m => trueStateAt.exists(at => now - at < m.trueStateFresh.toNanos))

    /** A readable control packet that counts (broadcast, or the true state): the gate, the budget, the view. */
    private def control(data: GameControlData, from: InetSocketAddress, now: Long): Unit = {
      gcPackets += 1
      gameFrom = Some(from)
      if (settings.teamMessages.enabled) budget = budget.game(data)
      val changed = !game.exists(_.gameState == data.gameState)
      gate(CompetitionGate.reading(data.gameState, data.version, lastUnreadable, now))
      // The 2014 GameController sends versions 8 and 7 each round; the richer (newer) packet is the one to keep.
      if (game.forall(g => rank(data.version) <= rank(g.version)) || changed) {
        game = Some(data)
        publish(GameStateUpdated(data))
      }
    }
    private var budget = MessageBudget(settings.teamMessages)

    /** Notes the sender of a readable control packet; true when its game state counts (see GameControllerSources). */
    private def heard(data: GameControlData, from: InetSocketAddress, trusted: Boolean, now: Long): Boolean = {
      val (next, use) = sources.packet(from, data.packetNumberOnWire, trusted, now)
      if (next.others(now).nonEmpty && sources.others(now).isEmpty)
        context.log.warn("{}", next.warnings(now).mkString("; "))
      sources = next
      use
    }

    /** Where a version stands among those read: newest (richest) first. */
    private def rank(version: GameControlVersion): Int = GameControlVersion.all.indexOf(version)

    /**
     * Every packet, not only changes, reaches the one gate (the outbox's, for both transports): a restarted outbox
     * learns the reading within one round; and it reaches it before any subscriber hears of the game, so a subscriber
     * reacting to kick-off finds it closed.
     */
    private def gate(reading: GameReading): Unit = {
      outbox ! Outbox.GameStateChanged(reading)
    }

    private def discoveredRobots: Int = byId.valuesIterator.count(_.discovered)

    /** The configured robots, then the reader: it never sees a table without them. */
    def start(): Unit = {
      settings.robots.foreach(r => spawnRobot(r.robotId, r.address, discovered = false))
      settings.zeromq.robots.foreach(spawnZeroMqRobot)
      port.start(reader)
    }

    def bindingGameController: Behavior[Command] = Behaviors.receiveMessage[Command] {
      case GameControllerEvent(UdpLink.Bound(gcLink, gcLocal)) =>
        context.log.info("Gateway listening for the GameController on {}", gcLocal)
        gameControllerAddress = Some(gcLocal)
        settings.monitor.foreach(startMonitor(gcLink, _))
        stash.unstashAll(running(Addresses(port.localAddress, Some(gcLocal))))
      case GameControllerEvent(UdpLink.BindFailed(address, reason)) =>
        context.log.error("GameController listener cannot bind {}: {}; game state will be unknown", address, reason)
        stash.unstashAll(running(Addresses(port.localAddress, None)))
      case u: Unrouted =>
        // Robots speak before the GameController socket is bound; discovery must not wait for it.
        handleUnrouted(u)
        Behaviors.same
      case other =>
        stash.stash(other)
        Behaviors.same
    }.receiveSignal { case (_, PostStop) => closePort() }

    private def closePort(): Behavior[Command] = {
      port.close()
      // After the port: nothing more is handed to the recording, and what waits is written before the file closes.
      recording.close()
      Behaviors.same
    }

    /** The routing table the reader uses from now on: every datagram robot at its bound IP address. */
    private def publishRoutes(): Unit =
      routes.set(Routing.Table.of(byId.collect {
        case (id, e) if !e.zeromq => Routing.Route(id, e.address.getAddress, Inlet(e.actor, e.backlog, e.signatures))
      }))

    private def robotRefs: Map[Int, (ActorRef[RobotActor.Command], InetSocketAddress)] =
      byId.map { case (id, e) => id -> (e.actor -> e.address) }

    private def spawnRobot(robotId: Int, address: InetSocketAddress, discovered: Boolean): Entry = {
      val backlog = new Backlog(settings.robotBacklog)
      val actor = context.spawn(
        Behaviors.supervise(RobotActor(robotId, address, settings, outbox, wiring(backlog), heard = false, discovered = discovered))
          .onFailure(settings.supervision.robot.strategy),
        s"robot-$robotId",
        RobotDispatcher
      )
      context.watchWith(actor, RobotStopped(robotId, actor))
      val signatures = settings.signingKey.filter(_ => settings.signingOf(robotId) == RobotSigning.Required).map(new SignatureCheck(_))
      val entry = Entry(actor, address, zeromq = false, backlog, signatures, discovered)
      byId = byId.updated(robotId, entry)
      byAddress = byAddress.updated(address.getAddress, robotId)
      publishRoutes()
      entry
    }

    // The robot actor asks for the subscribers itself (RobotWantsSubscribers), on its first start and after restarts.
    private def wiring(backlog: Backlog): RobotActor.Wiring = RobotActor.Wiring(Set.empty, Some(subscriptionRequests), backlog)

    /** A ZeroMQ robot: known by id only; no datagram is ever routed to it by address. */
    private def spawnZeroMqRobot(robot: ZeroMqRobot): Unit = {
      val backlog = new Backlog(settings.robotBacklog)
      val actor = context.spawn(
        Behaviors.supervise(RobotActor(robot.robotId, robot.address, settings, outbox, wiring(backlog), heard = false,
          RobotActor.Transport.ZeroMq(robot.endpoint)))
          .onFailure(settings.supervision.robot.strategy),
        s"robot-${robot.robotId}",
        RobotDispatcher
      )
      context.watchWith(actor, RobotStopped(robot.robotId, actor))
      byId = byId.updated(robot.robotId, Entry(actor, robot.address, zeromq = true, backlog))
    }

    private def reject(kind: Rejection, from: InetSocketAddress, detail: => String = ""): Unit = rejections.count(kind, from, detail)

    /** A link's datagrams over its cap, dropped unread: counted as the gateway being busy, with the last sender. */
    private def overCap(dropped: UdpLink.Dropped, port: String): Unit =
      rejections.count(Rejection.GatewayBusy, dropped.lastFrom, s"${dropped.count} datagrams over the cap of the $port port", dropped.count)

    private def rejectFor(robotId: Option[Int], kind: Rejection, from: InetSocketAddress, detail: => String): Unit = {
      reject(kind, from, detail)
      robotId.flatMap(byId.get).foreach { e =>
        e.backlog.add()
        e.actor ! RobotActor.DatagramRejected(kind)
      }
    }

    private def publish(event: GatewayEvent): Unit = subscribers.foreach(_ ! event)

    /** Every robot actor learns the new subscriber list: robot events go from them straight to the subscribers. */
    private def subscribersChanged(): Unit = byId.values.foreach(_.actor ! RobotActor.Subscribers(subscribers))

    /** Records a GameController packet (every one, before any check); true, so it can guard the first case. */
    private def recordGameController(bytes: Array[Byte], from: InetSocketAddress): Boolean = {
      if (recording.enabled)
        recording.datagram(RecordedPort.GAME_CONTROLLER, received = true, from, gameControllerAddress.orNull, bytes,
          byAddress.get(from.getAddress).getOrElse(-1))
      true
    }

    private def handleUnrouted(u: Unrouted): Unit = {
      gatewayBacklog.done()
      val f = u.frame
      // A robot that must sign: the reader's check, here before any delivery or re-binding (an address proves nothing).
      byId.get(f.contents.robotId).flatMap(_.signatures).map(_.check(f.bytes, f.header)) match {
        case Some(Left(kind)) => rejectFor(Some(f.contents.robotId), kind, f.from, s"robot id ${f.contents.robotId}")
        case _                => frame(f.header, f.contents, f.size, f.from)
      }
    }

    def running(addresses: Addresses): Behavior[Command] =
      Behaviors.receiveMessage[Command] {
        case u: Unrouted =>
          handleUnrouted(u)
          Behaviors.same
        case GameControllerEvent(UdpLink.Received(bytes, from)) if recordGameController(bytes, from) && Datagram.isGameControllerReturn(bytes) =>
          Behaviors.same // robots' answers to the GameController share its port
        case GameControllerEvent(UdpLink.Received(bytes, from)) if !settings.gameControllerTrusted.trusts(from.getAddress) =>
          // Anyone on the field's WiFi can send a control packet: only the configured GameController steers the gate.
          // A readable one is still noted, so a second GameController on the field is seen and named.
          gameUntrusted += 1
          reject(Rejection.UntrustedGameController, from)
          GameControllerCodec.decodeControl(bytes).foreach(heard(_, from, trusted = false, System.nanoTime()))
          Behaviors.same
        case GameControllerEvent(d: UdpLink.Dropped) =>
          overCap(d, "GameController")
          Behaviors.same
        case TeamMessageEvent(d: UdpLink.Dropped) =>
          overCap(d, "team message")
          Behaviors.same
        case MonitorStatusEvent(d: UdpLink.Dropped) =>
          overCap(d, "monitor status")
          Behaviors.same
        case TeamMessageEvent(UdpLink.Received(bytes, _)) =>
          budget = budget.message(bytes.length, System.nanoTime())
          Behaviors.same
        case TeamMessageEvent(UdpLink.BindFailed(address, reason)) =>
          context.log.error("Team message listener cannot bind {}: {}; the message budget will not be counted", address, reason)
          Behaviors.same
        case TeamMessageEvent(_) => Behaviors.same
        case MonitorStatusEvent(UdpLink.Received(bytes, from)) =>
          // Only the GameController forwards status messages; a stranger cannot fill the view.
          if (!settings.monitor.exists(_.gameController.getAddress == from.getAddress))
            reject(Rejection.UntrustedGameController, from, "status message from another host than the GameController")
          else
            GameControllerCodec.decodeForwardedStatus(bytes) match {
              case Right((robot, status)) => forwarded = forwarded.add(ForwardedStatus(robot, status, System.nanoTime()))
              case Left(error)            => reject(Rejection.BadGameControllerPacket, from, error.describe)
            }
          Behaviors.same
        case MonitorStatusEvent(UdpLink.BindFailed(address, reason)) =>
          context.log.error("Monitor status listener cannot bind {}: {}; forwarded robot statuses will not be shown", address, reason)
          Behaviors.same
        case MonitorStatusEvent(_) => Behaviors.same
        case GameControllerEvent(UdpLink.Received(bytes, from)) =>
          val now = System.nanoTime()
          GameControllerCodec.decodeControl(bytes) match {
            case Right(data) if !heard(data, from, trusted = true, now) =>
              // A second trusted GameController while the first keeps sending: named in the warnings, never obeyed.
              reject(Rejection.UntrustedGameController, from, "a second GameController")
            case Right(_) if trueStateFresh(now) =>
              // The monitor role: the broadcast state may lag the true one by up to 10 s; the true one rules meanwhile.
              gcPackets += 1
            case Right(data) => control(data, from, now)
            case Left(_) if settings.monitor.exists(_.gameController.getAddress == from.getAddress) &&
                GameControllerCodec.decodeTrueData(bytes).isRight =>
              control(GameControllerCodec.decodeTrueData(bytes).toOption.get, from, now)
              trueStateAt = Some(now)
            case Left(error) if Datagram.isGameControllerControl(bytes) =>
              // The trusted GameController sends what this gateway cannot read (a version yet to come): it may well be
              // running a game, so the gate closes (fail safe) and says why, rather than stay open as if none were.
              reject(Rejection.BadGameControllerPacket, from, error.describe)
              lastUnreadable = Some(now -> error.describe)
              gate(GameReading.Unreadable(error.describe))
            case Left(error) =>
              reject(Rejection.BadGameControllerPacket, from, error.describe)
          }
          Behaviors.same
        case GameControllerEvent(_) => Behaviors.same
        case Subscribe(subscriber) =>
          context.watchWith(subscriber, SubscriberGone(subscriber))
          subscribers += subscriber
          subscribersChanged()
          Behaviors.same
        case Unsubscribe(subscriber) =>
          context.unwatch(subscriber)
          subscribers -= subscriber
          subscribersChanged()
          Behaviors.same
        case SubscriberGone(subscriber) =>
          subscribers -= subscriber
          subscribersChanged()
          Behaviors.same
        case RobotWantsSubscribers(RobotActor.SubscribersWanted(robot)) =>
          robot ! RobotActor.Subscribers(subscribers)
          Behaviors.same
        case GetAddresses(replyTo) =>
          replyTo ! addresses
          Behaviors.same
        case GetRobots(replyTo) =>
          if (byId.isEmpty) replyTo ! Vector.empty
          else
            context.spawnAnonymous(Collector(robotRefs, settings.snapshotTimeout, replyTo ! (_: Vector[RobotSnapshot]))(RobotActor.GetSnapshot(_), (s: RobotSnapshot) => s.robotId,
              (id, address) => Some(RobotSnapshot(id, address))))
          Behaviors.same
        case GetLinkStats(replyTo) =>
          if (byId.isEmpty) replyTo ! RobotLinks(Vector.empty)
          else
            context.spawnAnonymous(Collector(robotRefs, settings.snapshotTimeout, (l: Vector[LinkStats]) => replyTo ! RobotLinks(l))(RobotActor.GetLinkStats(_),
              (l: LinkStats) => l.robotId, (_, _) => None))
          Behaviors.same
        case GetRobot(robotId, replyTo) =>
          replyTo ! byId.get(robotId).map(_.actor)
          Behaviors.same
        case AllowRebind(robotId) =>
          rebindable += robotId
          Behaviors.same
        case GetStats(replyTo) =>
          replyTo ! GatewayStats(reader.datagramsIn, reader.relayed, gcPackets, rejections.snapshot, byId.size, rejections.sources,
            recording.stats, port match { case r: ReplayLink => Some(r.progress); case _ => None })
          Behaviors.same
        case GetTraffic(replyTo) =>
          outbox ! Outbox.GetStats(replyTo)
          Behaviors.same
        case GetGameState(replyTo) =>
          replyTo ! game
          Behaviors.same
        case GetGameSource(replyTo) =>
          val now = System.nanoTime()
          replyTo ! GameSource(settings.gameControllerTrusted.describe, gameFrom, gameUntrusted,
            Option.when(settings.teamMessages.enabled)(budget.describe(now)),
            sources.warnings(now) ++ (if (settings.teamMessages.enabled) budget.warnings(now) else Vector.empty),
            trueStateAt.map(at => (now - at) / 1000000L), forwarded.sorted)
          Behaviors.same
        case RobotStopped(robotId, actor) =>
          // A forgotten robot: its IP address, its id and its traffic meter are free again.
          byId.get(robotId).filter(_.actor == actor).foreach { e =>
            if (!e.zeromq) byAddress -= e.address.getAddress
            byId -= robotId
            rebindable -= robotId
            outbox ! Outbox.RobotGone(robotId)
            publishRoutes()
          }
          Behaviors.same
      }.receiveSignal { case (_, PostStop) => closePort() }

    /**
     * Decides a frame the reader's table could not place, binding a robot id to the IP address it first came from.
     * Everything sent to the robot goes to that IP at the robot's receive port, never to the frame's source port.
     */
    private def frame(header: FrameHeader, contents: MessageContents, size: Int, from: InetSocketAddress): Unit = {
      val robotId = contents.robotId
      val ip = from.getAddress
      def deliver(entry: Entry): Unit = {
        entry.backlog.add()
        entry.actor ! RobotActor.FrameReceived(contents, header.form, size)
      }
      byId.get(robotId) match {
        case Some(entry) if entry.zeromq =>
          rejectFor(Some(robotId), Rejection.ZeroMqRobotId, from, s"robot id $robotId")
        // The reader saw the table before the gateway bound this IP (discovery or re-bind in between).
        case Some(entry) if entry.address.getAddress == ip => deliver(entry)
        case Some(entry) if rebindable(robotId) && !byAddress.contains(ip) =>
          // An explicit re-bind: the robot moved to another host. It keeps its receive port.
          rebindable -= robotId
          val to = new InetSocketAddress(ip, entry.address.getPort)
          byAddress = byAddress - entry.address.getAddress + (ip -> robotId)
          val moved = entry.copy(address = to)
          byId = byId.updated(robotId, moved)
          publishRoutes()
          entry.actor ! RobotActor.Rebound(to)
          deliver(moved)
        case Some(entry) =>
          rejectFor(Some(robotId), Rejection.RobotIdMismatch, from, s"robot id $robotId claimed from another address than ${entry.address.getAddress.getHostAddress}")
        case None =>
          byAddress.get(ip) match {
            case Some(other) => rejectFor(Some(other), Rejection.RobotIdMismatch, from, s"address of robot $other claims robot id $robotId")
            case None if settings.discovery.enabled && contents.status.isDefined =>
              if (discoveredRobots >= settings.discovery.maxRobots)
                // Anyone can invent robot ids: what they create is bounded, the rest is counted (and logged rarely).
                reject(Rejection.RobotCapReached, from, s"robot id $robotId")
              else {
                // The robot receives at its IP on the receive port (docs/protocol.md section 2), not at this source port.
                val at = new InetSocketAddress(ip, settings.robotReceivePort)
                context.log.info("Discovered robot [{}] at {} (sending from {})", robotId, at, from)
                deliver(spawnRobot(robotId, at, discovered = true))
              }
            case None => reject(Rejection.UnknownSender, from, s"robot id $robotId")
          }
      }
    }
  }

  /**
   * One question to every robot actor (`GetRobots`, `GetLinkStats`): asks each, and answers once all did or
   * `timeout` (`snapshot-timeout`) passed. A robot actor that did not answer in time (restarting) is listed by `missing`.
   */
  private object Collector {
    sealed trait Message
    private final case class Got[A](robotId: Int, answer: A) extends Message
    private case object TimedOut extends Message

    def apply[A: ClassTag](robots: Map[Int, (ActorRef[RobotActor.Command], InetSocketAddress)], timeout: FiniteDuration,
        replyTo: Vector[A] => Unit)(
        ask: ActorRef[A] => RobotActor.Command, idOf: A => Int, missing: (Int, InetSocketAddress) => Option[A]): Behavior[Message] =
      Behaviors.setup[Message] { context =>
        Behaviors.withTimers { timers =>
          // One adapter for the one reply class this collector waits for.
          val got = context.messageAdapter[A](a => Got(idOf(a), a))
          robots.values.foreach { case (actor, _) => actor ! ask(got) }
          timers.startSingleTimer(TimedOut, timeout)
          def answer(known: Map[Int, A]): Behavior[Message] = {
            replyTo(robots.toVector.sortBy(_._1).flatMap { case (id, (_, address)) => known.get(id).orElse(missing(id, address)) })
            Behaviors.stopped
          }
          def collecting(known: Map[Int, A]): Behavior[Message] = Behaviors.receiveMessage {
            case g: Got[A @unchecked] =>
              val now = known.updated(g.robotId, g.answer)
              if (robots.keySet.forall(now.contains)) answer(now) else collecting(now)
            case TimedOut => answer(known)
          }
          collecting(Map.empty)
        }
      }
  }
}
