package naogateway.gateway

import java.net.{InetAddress, InetSocketAddress}
import java.util.concurrent.atomic.AtomicReference

import akka.actor.typed.scaladsl.{ActorContext, Behaviors, StashBuffer}
import akka.actor.typed.{ActorRef, Behavior, PostStop}

import naogateway.access.{GatewayAccess, RobotAccess}
import naogateway.api.{GameReading, GatewayAddresses, GatewayEvent, GatewayStats, LinkStats, RobotLinks, RobotSnapshot}
import naogateway.gateway.gamecontroller.GameControllerWatch
import naogateway.gateway.link.{Backlog, PortProgress, PortReader, Relay, ReplayLink, RobotLink, UdpLink}
import naogateway.gateway.recording.{Recording, RobotClockEstimates}
import naogateway.gateway.tap.Tap
import naogateway.gateway.robot.{Outbox, RobotActor, RobotRef, RobotTransport, RobotWiring}
import naogateway.proto.RecordedPort
import naogateway.wire._

/** The gateway's logic behind its protocol (`Gateway`): the robot registry (configured, ZeroMQ and discovered robots,
  * by id and by IP address, and the routing table the port's reader uses), the frames the reader could not place, the
  * GameController's, team and monitor ports' datagrams, the event subscribers, and the answers to the public protocol.
  */
private[naogateway] final class GatewayLogic(
    settings: GatewaySettings,
    context: ActorContext[Gateway.Command],
    stash: StashBuffer[Gateway.Command],
    port: RobotLink,
    outbox: ActorRef[Outbox.Command],
    tap: Tap,
    recording: Recording,
    relay: Option[Relay],
    routes: AtomicReference[Routing.Table[PortReader.Inlet]],
    clocks: RobotClockEstimates,
    signing: Option[GatewaySigning]
) {
  import Gateway._

  private val subscriptionRequests = context.messageAdapter[RobotActor.SubscribersWanted](RobotWantsSubscribers.apply)
  private val rejections = new RejectionLedger.Shared
  private val gatewayBacklog = new Backlog(settings.gatewayBacklog)
  // How far the reader has caught up with the robot port, for the heartbeats of the robots it carries.
  private val portProgress = new PortProgress
  private val reader =
    new PortReader(port, context.self, gatewayBacklog, outbox, rejections, tap, routes, portProgress)
  private var gameControllerAddress: Option[InetSocketAddress] = None
  private var byId = Map.empty[Int, Entry]
  // Keyed by IP alone: a robot's source port changes when its module reconnects, its IP does not.
  private var byAddress = Map.empty[InetAddress, Int]
  // The recorder's subscriber: every event but the keep-alives' status (the recorder reads the status off the tap, and
  // the robot actors put the clock estimates in `clocks` themselves).
  private val recorderEvents: Set[ActorRef[GatewayEvent]] =
    if (recording.enabled) Set(context.spawn(recordingEvents(tap), "recording-events", RobotDispatcher))
    else Set.empty
  private var subscribers: Set[ActorRef[GatewayEvent]] = recorderEvents
  private val watch = new GameControllerWatch(settings, context, rejections, gate, publish)

  /** Every packet, not only changes, reaches the one gate (the outbox's, for both transports): a restarted outbox
    * learns the reading within one round; and it reaches it before any subscriber hears of the game, so a subscriber
    * reacting to kick-off finds it closed.
    */
  private def gate(reading: GameReading): Unit = {
    outbox ! Outbox.GameStateChanged(reading)
  }

  private def discoveredRobots: Int = byId.valuesIterator.count(_.discovered)

  /** The configured robots, then the reader: it never sees a table without them. */
  def start(): Unit = {
    watch.start()
    settings.robots.foreach(r => spawnRobot(r.robotId, r.address, discovered = false))
    settings.zeromq.robots.foreach(spawnZeroMqRobot)
    // On the robot dispatcher's own thread when it is a port loop (reference.conf): a robot's answer then wakes one
    // thread, the one that runs its actors.
    port.startOn(reader, context.system.dispatchers.lookup(RobotDispatcher))
  }

  def bindingGameController: Behavior[Command] = Behaviors.receiveMessage[Command] {
    case GameControllerEvent(UdpLink.Bound(gcLink, gcLocal)) =>
      context.log.info("Gateway listening for the GameController on {}", gcLocal)
      gameControllerAddress = Some(gcLocal)
      settings.monitor.foreach(watch.startMonitor(gcLink, _))
      stash.unstashAll(running(GatewayAddresses(port.localAddress, Some(gcLocal))))
    case GameControllerEvent(UdpLink.BindFailed(address, reason)) =>
      context.log.error("GameController listener cannot bind {}: {}; game state will be unknown", address, reason)
      stash.unstashAll(running(GatewayAddresses(port.localAddress, None)))
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
    // After the port: nothing more is published, and what waits is written before the file closes.
    relay.foreach(_.close())
    recording.close()
    Behaviors.same
  }

  /** The routing table the reader uses from now on: every datagram robot at its bound IP address. */
  private def publishRoutes(): Unit =
    routes.set(Routing.Table.of(byId.collect {
      case (id, e) if !e.zeromq =>
        Routing.Route(id, e.address.getAddress, PortReader.Inlet(e.actor.own, e.backlog, e.signatures))
    }))

  private def robotRefs: Map[Int, (ActorRef[RobotAccess.Question], InetSocketAddress)] =
    byId.map { case (id, e) => id -> (e.actor.access -> e.address) }

  private def spawnRobot(robotId: Int, address: InetSocketAddress, discovered: Boolean): Entry = {
    val backlog = new Backlog(settings.robotBacklog)
    val actor = RobotRef(context.spawn(
        Behaviors.supervise(RobotActor(robotId, address, settings, outbox,
            wiring(backlog).copy(port = portProgress), heard = false, discovered = discovered))
          .onFailure(settings.supervision.robot.strategy),
        s"robot-$robotId",
        RobotDispatcher
      ))
    context.watchWith(actor.own, RobotStopped(robotId, actor.own))
    val signatures = signing.filter(_ => settings.signingOf(robotId) == RobotSigning.Required).map(_.robot(robotId))
    val entry = Entry(actor, address, zeromq = false, backlog, signatures, discovered)
    byId = byId.updated(robotId, entry)
    byAddress = byAddress.updated(address.getAddress, robotId)
    publishRoutes()
    entry
  }

  // The robot actor asks for the subscribers itself (RobotWantsSubscribers), on its first start and after restarts.
  private def wiring(backlog: Backlog): RobotWiring =
    RobotWiring(Set.empty, Some(subscriptionRequests), backlog, clocks)

  /** A ZeroMQ robot: known by id only; no datagram is ever routed to it by address. */
  private def spawnZeroMqRobot(robot: ZeroMqRobot): Unit = {
    val backlog = new Backlog(settings.robotBacklog)
    val actor = RobotRef(context.spawn(
        Behaviors.supervise(RobotActor(robot.robotId, robot.address, settings, outbox, wiring(backlog), heard = false,
            RobotTransport.ZeroMq(robot.endpoint)))
          .onFailure(settings.supervision.robot.strategy),
        s"robot-${robot.robotId}",
        RobotDispatcher
      ))
    context.watchWith(actor.own, RobotStopped(robot.robotId, actor.own))
    byId = byId.updated(robot.robotId, Entry(actor, robot.address, zeromq = true, backlog))
  }

  private def reject(kind: Rejection, from: InetSocketAddress, detail: => String): Unit =
    rejections.count(kind, from, detail)

  /** A link's datagrams over its cap, dropped unread: counted as the gateway being busy, with the last sender. */
  private def overCap(dropped: UdpLink.Dropped, port: String): Unit =
    rejections.count(Rejection.GatewayBusy, dropped.lastFrom,
      s"${dropped.count} datagrams over the cap of the $port port", dropped.count)

  private def rejectFor(robotId: Option[Int], kind: Rejection, from: InetSocketAddress, detail: => String): Unit = {
    reject(kind, from, detail)
    robotId.flatMap(byId.get).foreach { e =>
      e.backlog.add()
      e.actor.own ! RobotActor.DatagramRejected(kind)
    }
  }

  private def publish(event: GatewayEvent): Unit = subscribers.foreach(_ ! event)

  /** The subscribers as a robot actor publishes to them: the recorder gets no status. */
  private def robotSubscribers: RobotActor.Subscribers = RobotActor.Subscribers(subscribers, recorderEvents)

  /** Every robot actor learns the new subscriber list: robot events go from them straight to the subscribers. */
  private def subscribersChanged(): Unit = byId.values.foreach(_.actor.own ! robotSubscribers)

  /** Records a GameController packet (every one, before any check); true, so it can guard the first case. */
  private def recordGameController(bytes: Array[Byte], from: InetSocketAddress): Boolean = {
    if (tap.listening)
      tap.datagram(RecordedPort.GAME_CONTROLLER, received = true, from, gameControllerAddress.orNull, bytes,
        byAddress.get(from.getAddress).getOrElse(-1))
    true
  }

  private def handleUnrouted(u: Unrouted): Unit = {
    gatewayBacklog.done()
    val f = u.frame
    // A robot that must sign: the reader's check, here before any delivery, re-binding or discovery (an address
    // proves nothing). A robot not known yet is discovered only by a keep-alive signed with its own key.
    val robotId = f.contents.robotId
    val verdict = byId.get(robotId) match {
      case Some(entry) => entry.signatures.map(_.check(f.bytes, f.header))
      case None =>
        signing.filter(_ => settings.signingOf(robotId) == RobotSigning.Required).map(
          _.checkNew(robotId, f.bytes, f.header))
    }
    verdict match {
      case Some(Left(kind)) => rejectFor(Some(f.contents.robotId), kind, f.from, s"robot id ${f.contents.robotId}")
      case _                => frame(f.header, f.contents, f.size, f.from)
    }
  }

  def running(addresses: GatewayAddresses): Behavior[Command] =
    Behaviors.receiveMessage[Command] {
      case u: Unrouted =>
        handleUnrouted(u)
        Behaviors.same
      case GameControllerEvent(UdpLink.Received(bytes, from))
          if recordGameController(bytes, from) && Datagram.isGameControllerReturn(bytes) =>
        Behaviors.same // robots' answers to the GameController share its port
      case GameControllerEvent(UdpLink.Received(bytes, from))
          if !settings.gameControllerTrusted.trusts(from.getAddress) =>
        watch.untrustedPacket(bytes, from)
        Behaviors.same
      case GameControllerEvent(d: UdpLink.Dropped) =>
        overCap(d, "GameController")
        if (d.trusted) watch.trustedDropped(d.count)
        Behaviors.same
      case TeamMessageEvent(d: UdpLink.Dropped) =>
        overCap(d, "team message")
        Behaviors.same
      case MonitorStatusEvent(d: UdpLink.Dropped) =>
        overCap(d, "monitor status")
        Behaviors.same
      case TeamMessageEvent(UdpLink.Received(bytes, _)) =>
        watch.teamMessage(bytes)
        Behaviors.same
      case TeamMessageEvent(UdpLink.BindFailed(address, reason)) =>
        context.log.error("Team message listener cannot bind {}: {}; the message budget will not be counted", address,
          reason)
        Behaviors.same
      case TeamMessageEvent(_) => Behaviors.same
      case MonitorStatusEvent(UdpLink.Received(bytes, from)) =>
        watch.forwardedStatus(bytes, from)
        Behaviors.same
      case MonitorStatusEvent(UdpLink.BindFailed(address, reason)) =>
        context.log.error("Monitor status listener cannot bind {}: {}; forwarded robot statuses will not be shown",
          address, reason)
        Behaviors.same
      case MonitorStatusEvent(_) => Behaviors.same
      case GameControllerEvent(UdpLink.Received(bytes, from)) =>
        watch.trustedPacket(bytes, from)
        Behaviors.same
      case GameControllerEvent(_) => Behaviors.same
      case RobotWantsSubscribers(RobotActor.SubscribersWanted(robot)) =>
        robot ! robotSubscribers
        Behaviors.same
      case SubscriberGone(subscriber) =>
        subscribers -= subscriber
        subscribersChanged()
        Behaviors.same
      case AccessRequest(request) =>
        accessRequest(request, addresses)
        Behaviors.same
      case GetRobot(robotId, replyTo) =>
        replyTo ! byId.get(robotId).map(_.actor.own)
        Behaviors.same
      case RobotStopped(robotId, actor) =>
        // A forgotten robot: its IP address, its id and its traffic meter are free again.
        byId.get(robotId).filter(_.actor.own == actor).foreach { e =>
          if (!e.zeromq) byAddress -= e.address.getAddress
          byId -= robotId
          outbox ! Outbox.RobotGone(robotId)
          publishRoutes()
        }
        Behaviors.same
    }.receiveSignal { case (_, PostStop) => closePort() }

  /** A message of the public protocol: the middleware's and the operator tools'. */
  private def accessRequest(request: GatewayAccess.Command, addresses: GatewayAddresses): Unit = request match {
    case GatewayAccess.Subscribe(subscriber) =>
      context.watchWith(subscriber, SubscriberGone(subscriber))
      subscribers += subscriber
      subscribersChanged()
    case GatewayAccess.Unsubscribe(subscriber) =>
      context.unwatch(subscriber)
      subscribers -= subscriber
      subscribersChanged()
    case GatewayAccess.GetAddresses(replyTo) =>
      replyTo ! addresses
    case GatewayAccess.GetRobots(replyTo) =>
      if (byId.isEmpty) replyTo ! Vector.empty
      else
        context.spawnAnonymous(Collector(robotRefs, settings.snapshotTimeout, replyTo ! (_: Vector[RobotSnapshot]))(
            RobotAccess.GetSnapshot(_), (s: RobotSnapshot) => s.robotId,
            (id, address) => Some(RobotSnapshot(id, address))))
    case GatewayAccess.GetLinkStats(replyTo) =>
      if (byId.isEmpty) replyTo ! RobotLinks(Vector.empty)
      else
        context.spawnAnonymous(Collector(robotRefs, settings.snapshotTimeout,
            (l: Vector[LinkStats]) => replyTo ! RobotLinks(l))(RobotAccess.GetLinkStats(_),
            (l: LinkStats) => l.robotId, (_, _) => None))
    case GatewayAccess.GetRobotAccess(robotId, replyTo) =>
      replyTo ! byId.get(robotId).map(_.actor.access)
    case GatewayAccess.GetStats(replyTo) =>
      val ledger = rejections.current
      replyTo ! GatewayStats(
        reader.datagramsIn,
        relay.fold(0L)(_.relayed),
        watch.packetsCounted,
        ledger.byKind,
        byId.size,
        ledger.sources,
        recording.stats,
        port match { case r: ReplayLink => Some(r.progress); case _ => None },
        tap.readers
      )
    case GatewayAccess.GetTap(replyTo) =>
      replyTo ! tap
    case GatewayAccess.GetTraffic(replyTo) =>
      outbox ! Outbox.GetStats(replyTo)
    case GatewayAccess.GetGameState(replyTo) =>
      replyTo ! watch.state
    case GatewayAccess.GetGameSource(replyTo) =>
      replyTo ! watch.source(System.nanoTime())
  }

  /** Decides a frame the reader's table could not place, binding a robot id to the IP address it first came from.
    * Everything sent to the robot goes to that IP at the robot's receive port, never to the frame's source port.
    */
  private def frame(header: FrameHeader, contents: MessageContents, size: Int, from: InetSocketAddress): Unit = {
    val robotId = contents.robotId
    val ip = from.getAddress
    def deliver(entry: Entry): Unit = {
      entry.backlog.add()
      entry.actor.own ! RobotActor.FrameReceived(contents, header.form, size)
    }
    byId.get(robotId) match {
      case Some(entry) if entry.zeromq =>
        rejectFor(Some(robotId), Rejection.ZeroMqRobotId, from, s"robot id $robotId")
      // The reader saw the table before the gateway bound this IP (discovery in between).
      case Some(entry) if entry.address.getAddress == ip => deliver(entry)
      case Some(entry) =>
        rejectFor(Some(robotId), Rejection.RobotIdMismatch, from,
          s"robot id $robotId claimed from another address than ${entry.address.getAddress.getHostAddress}")
      case None =>
        byAddress.get(ip) match {
          case Some(other) => rejectFor(Some(other), Rejection.RobotIdMismatch, from,
              s"address of robot $other claims robot id $robotId")
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
