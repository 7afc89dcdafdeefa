package naogateway

import java.net.InetSocketAddress

import akka.actor.typed.scaladsl.{ActorContext, Behaviors, StashBuffer}
import akka.actor.typed.{ActorRef, Behavior, SupervisorStrategy}
import scala.concurrent.duration._

import naogateway.link.UdpLink
import naogateway.wire._
import naogateway.wire.gamecontroller.{GameControlData, GameControlVersion, GameControllerCodec}

/** The robot side of the middleware: the robots' UDP port, the robot registry, the GameController and the relay. */
object Gateway {

  /** What the gateway accepts. */
  sealed trait Command

  /** Answers with the bound addresses (the real ports when 0 was configured). */
  final case class GetAddresses(replyTo: ActorRef[Addresses]) extends Command

  /** Answers with the latest snapshot of every known robot. */
  final case class GetRobots(replyTo: ActorRef[Vector[RobotSnapshot]]) extends Command

  /** Answers with the robot actor of `robotId`, if the robot is known. */
  final case class GetRobot(robotId: Int, replyTo: ActorRef[Option[ActorRef[RobotActor.Command]]]) extends Command

  /** Lets robot `robotId` be re-bound to the address its next datagram comes from. */
  final case class AllowRebind(robotId: Int) extends Command

  /** Sends every `GatewayEvent` to `subscriber` until it stops. */
  final case class Subscribe(subscriber: ActorRef[GatewayEvent]) extends Command

  /** Stops sending events to `subscriber`. */
  final case class Unsubscribe(subscriber: ActorRef[GatewayEvent]) extends Command

  /** Answers with the gateway's own figures. */
  final case class GetStats(replyTo: ActorRef[GatewayStats]) extends Command

  /** Answers with the team traffic figures of the outbox. */
  final case class GetTraffic(replyTo: ActorRef[Outbox.TrafficStats]) extends Command

  /** Answers with the latest GameController packet, if any arrived. */
  final case class GetGameState(replyTo: ActorRef[Option[GameControlData]]) extends Command

  private final case class RobotLinkEvent(event: UdpLink.Event) extends Command
  private final case class GameControllerEvent(event: UdpLink.Event) extends Command
  private final case class Publish(event: GatewayEvent) extends Command
  private final case class SubscriberGone(subscriber: ActorRef[GatewayEvent]) extends Command
  private final case class RobotStopped(robotId: Int) extends Command

  /** Where the gateway listens. */
  final case class Addresses(robots: InetSocketAddress, gameController: Option[InetSocketAddress])

  /** The gateway's own figures: datagrams seen, relayed, refused by reason. */
  final case class GatewayStats(datagramsIn: Long, relayed: Long, gameControllerPackets: Long, rejected: Map[String, Long], robots: Int)

  private final case class Entry(actor: ActorRef[RobotActor.Command], address: InetSocketAddress, heard: Boolean, zeromq: Boolean = false)

  /** The gateway with `settings`. */
  def apply(settings: GatewaySettings): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withStash(1024) { stash =>
        context.spawn(
          UdpLink(new InetSocketAddress(settings.bindAddress, settings.robotPort), context.messageAdapter(RobotLinkEvent.apply)),
          "robot-link"
        )
        new GatewayLogic(settings, context, stash).binding
      }
    }

  private final class GatewayLogic(settings: GatewaySettings, context: ActorContext[Command], stash: StashBuffer[Command]) {
    private val publisher = context.messageAdapter[GatewayEvent](Publish.apply)
    private var byId = Map.empty[Int, Entry]
    private var byAddress = Map.empty[InetSocketAddress, Int]
    private var snapshots = Map.empty[Int, RobotSnapshot]
    private var subscribers = Set.empty[ActorRef[GatewayEvent]]
    private var rebindable = Set.empty[Int]
    private var rejected = Map.empty[String, Long]
    private var datagramsIn, relayed, gcPackets = 0L
    private var game: Option[GameControlData] = None

    def binding: Behavior[Command] = Behaviors.receiveMessage {
      case RobotLinkEvent(UdpLink.Bound(link, local)) =>
        context.log.info("Gateway listening for robots on {}", local)
        val outbox = context.spawn(
          Behaviors.supervise(Outbox(link, settings.budget, settings.competition))
            .onFailure(SupervisorStrategy.restartWithBackoff(100.millis, 5.seconds, 0.2)),
          "outbox"
        )
        settings.robots.foreach(r => spawnRobot(r.robotId, r.address, outbox, heard = false))
        settings.zeromq.robots.foreach(r => spawnZmqRobot(r, outbox))
        if (settings.gameControllerEnabled) {
          // Akka keeps one message adapter per message class, and the robot link's adapter already takes
          // UdpLink.Event; the GameController link reports through a forwarder of its own instead.
          val self = context.self
          val gcEvents = context.spawn(
            Behaviors.receiveMessage[UdpLink.Event] { event =>
              self ! GameControllerEvent(event)
              Behaviors.same
            },
            "game-controller-events"
          )
          context.spawn(
            UdpLink(new InetSocketAddress(settings.gameControllerBindAddress, settings.gameControllerPort), gcEvents,
              UdpLink.Options(reuseAddress = settings.gameControllerReuseAddress, broadcast = true)),
            "game-controller-link"
          )
          bindingGameController(link, local, outbox)
        } else stash.unstashAll(running(link, Addresses(local, None), outbox))
      case RobotLinkEvent(UdpLink.BindFailed(address, reason)) =>
        throw new IllegalStateException(s"gateway cannot listen for robots on $address: $reason")
      case other =>
        stash.stash(other)
        Behaviors.same
    }

    private def bindingGameController(link: ActorRef[UdpLink.Command], local: InetSocketAddress, outbox: ActorRef[Outbox.Command])
        : Behavior[Command] = Behaviors.receiveMessage {
      case GameControllerEvent(UdpLink.Bound(_, gcLocal)) =>
        context.log.info("Gateway listening for the GameController on {}", gcLocal)
        stash.unstashAll(running(link, Addresses(local, Some(gcLocal)), outbox))
      case GameControllerEvent(UdpLink.BindFailed(address, reason)) =>
        context.log.error("GameController listener cannot bind {}: {}; game state will be unknown", address, reason)
        stash.unstashAll(running(link, Addresses(local, None), outbox))
      case other =>
        stash.stash(other)
        Behaviors.same
    }

    private def spawnRobot(robotId: Int, address: InetSocketAddress, outbox: ActorRef[Outbox.Command], heard: Boolean): Entry = {
      val actor = context.spawn(
        Behaviors.supervise(RobotActor(robotId, address, settings, outbox, publisher, heard))
          .onFailure(SupervisorStrategy.restartWithBackoff(200.millis, 10.seconds, 0.2)),
        s"robot-$robotId"
      )
      context.watchWith(actor, RobotStopped(robotId))
      val entry = Entry(actor, address, heard)
      byId = byId.updated(robotId, entry)
      byAddress = byAddress.updated(address, robotId)
      snapshots = snapshots.updated(robotId, RobotSnapshot(robotId, address))
      entry
    }

    /** A ZeroMQ robot: known by id only; no datagram is ever routed to it by address. */
    private def spawnZmqRobot(robot: ZmqRobot, outbox: ActorRef[Outbox.Command]): Unit = {
      val actor = context.spawn(
        Behaviors.supervise(RobotActor(robot.robotId, robot.address, settings, outbox, publisher, heard = false,
          RobotActor.Transport.ZeroMq(robot.endpoint)))
          .onFailure(SupervisorStrategy.restartWithBackoff(200.millis, 10.seconds, 0.2)),
        s"robot-${robot.robotId}"
      )
      context.watchWith(actor, RobotStopped(robot.robotId))
      byId = byId.updated(robot.robotId, Entry(actor, robot.address, heard = false, zeromq = true))
      snapshots = snapshots.updated(robot.robotId, RobotSnapshot(robot.robotId, robot.address))
    }

    private def reject(reason: String, from: InetSocketAddress): Unit = {
      val n = rejected.getOrElse(reason, 0L) + 1
      rejected = rejected.updated(reason, n)
      // Logged at the 1st, 10th, 100th, ... of each reason: a flood of bad datagrams cannot flood the log.
      if (RateLimitedLog.due(n))
        context.log.warn("Rejected datagram from {}: {} ({} so far)", from, reason, n)
    }

    private def rejectFor(robotId: Option[Int], reason: String, from: InetSocketAddress): Unit = {
      reject(reason, from)
      robotId.flatMap(byId.get).foreach(_.actor ! RobotActor.DatagramRejected(reason))
    }

    private def publish(event: GatewayEvent): Unit = subscribers.foreach(_ ! event)

    def running(link: ActorRef[UdpLink.Command], addresses: Addresses, outbox: ActorRef[Outbox.Command]): Behavior[Command] =
      Behaviors.receiveMessage {
        case RobotLinkEvent(UdpLink.Received(bytes, from)) =>
          datagramsIn += 1
          settings.relay.foreach { relay =>
            relayed += 1
            link ! UdpLink.Send(bytes, relay)
          }
          val known = byAddress.get(from)
          outbox ! Outbox.Inbound(known.getOrElse(-1), bytes.length)
          Datagram.classify(bytes) match {
            case Datagram.FuRemoteFrame(_) =>
              MessageContents.decodeFrame(bytes) match {
                case Right((header, contents)) => frame(header, contents, bytes.length, from, outbox)
                case Left(error)               => rejectFor(known, s"bad frame: ${errorKind(error)}", from)
              }
            case Datagram.StreamSegment(_) =>
              known.flatMap(byId.get) match {
                case Some(entry) => entry.actor ! RobotActor.SegmentReceived(bytes)
                case None        => reject("stream segment from an unknown address", from)
              }
            case Datagram.GameControllerControl(_) | Datagram.GameControllerReturn(_) =>
              rejectFor(known, "GameController packet on the robot port", from)
            case Datagram.Rejected(reason, _) =>
              rejectFor(known, s"unclassifiable: ${reason.describe.takeWhile(_ != ':')}", from)
          }
          Behaviors.same
        case GameControllerEvent(UdpLink.Received(bytes, from)) =>
          GameControllerCodec.decodeControl(bytes) match {
            case Right(data) =>
              gcPackets += 1
              val changed = !game.exists(_.gameState == data.gameState)
              // Every packet, not only changes: a restarted outbox or ZeroMQ link learns the game state within one round.
              // Every gate (the outbox's, each ZeroMQ robot's) hears of it before any subscriber does, so a subscriber
              // reacting to kick-off finds them closed.
              outbox ! Outbox.GameStateChanged(data.gameState)
              byId.values.filter(_.zeromq).foreach(_.actor ! RobotActor.GameStateChanged(data.gameState))
              // Both versions arrive each round; the version-8 packet is the richer one to keep.
              if (data.version == GameControlVersion.V8 || game.forall(_.version != GameControlVersion.V8) || changed) {
                game = Some(data)
                publish(GameStateUpdated(data))
              }
            case Left(error) =>
              if (!Datagram.isGameControllerReturn(bytes)) reject(s"bad GameController packet: ${error.describe.takeWhile(_ != ':')}", from)
          }
          Behaviors.same
        case RobotLinkEvent(_) | GameControllerEvent(_) => Behaviors.same
        case Publish(event) =>
          snapshots = RobotSnapshot.following(snapshots, event)
          publish(event)
          Behaviors.same
        case Subscribe(subscriber) =>
          context.watchWith(subscriber, SubscriberGone(subscriber))
          subscribers += subscriber
          Behaviors.same
        case Unsubscribe(subscriber) =>
          context.unwatch(subscriber)
          subscribers -= subscriber
          Behaviors.same
        case SubscriberGone(subscriber) =>
          subscribers -= subscriber
          Behaviors.same
        case GetAddresses(replyTo) =>
          replyTo ! addresses
          Behaviors.same
        case GetRobots(replyTo) =>
          replyTo ! snapshots.values.toVector.sortBy(_.robotId)
          Behaviors.same
        case GetRobot(robotId, replyTo) =>
          replyTo ! byId.get(robotId).map(_.actor)
          Behaviors.same
        case AllowRebind(robotId) =>
          rebindable += robotId
          Behaviors.same
        case GetStats(replyTo) =>
          replyTo ! GatewayStats(datagramsIn, relayed, gcPackets, rejected, byId.size)
          Behaviors.same
        case GetTraffic(replyTo) =>
          outbox ! Outbox.GetStats(replyTo)
          Behaviors.same
        case GetGameState(replyTo) =>
          replyTo ! game
          Behaviors.same
        case RobotStopped(robotId) =>
          byId.get(robotId).filterNot(_.zeromq).foreach(e => byAddress -= e.address)
          byId -= robotId
          Behaviors.same
      }

    private def errorKind(error: FrameError): String = error.productPrefix

    /** Routes one decoded frame, binding a robot id to the address it first came from. */
    private def frame(header: FrameHeader, contents: MessageContents, size: Int, from: InetSocketAddress, outbox: ActorRef[Outbox.Command])
        : Unit = {
      val robotId = contents.robotId
      def deliver(entry: Entry): Unit = entry.actor ! RobotActor.FrameReceived(contents, header.form, size)
      byId.get(robotId) match {
        case Some(entry) if entry.zeromq =>
          rejectFor(Some(robotId), s"robot id $robotId belongs to a ZeroMQ robot", from)
        case Some(entry) if entry.address == from => deliver(entry)
        case Some(entry) if rebindable(robotId) || (!entry.heard && entry.address.getAddress == from.getAddress) =>
          // An explicit re-bind, or a configured robot speaking for the first time from its own host.
          rebindable -= robotId
          byAddress = byAddress - entry.address + (from -> robotId)
          val moved = entry.copy(address = from, heard = true)
          byId = byId.updated(robotId, moved)
          entry.actor ! RobotActor.Rebound(from)
          deliver(moved)
        case Some(entry) =>
          rejectFor(Some(robotId), s"robot id $robotId claimed from another address than ${entry.address}", from)
        case None =>
          byAddress.get(from) match {
            case Some(other) => rejectFor(Some(other), s"address of robot $other claims robot id $robotId", from)
            case None if settings.discoverFromKeepAlive && contents.status.isDefined =>
              context.log.info("Discovered robot [{}] at {}", robotId, from)
              deliver(spawnRobot(robotId, from, outbox, heard = true))
            case None => reject("frame from an unknown robot that is not a keep-alive", from)
          }
      }
    }
  }
}
