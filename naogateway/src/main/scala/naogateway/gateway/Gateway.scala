package naogateway.gateway

import java.net.InetSocketAddress
import java.util.concurrent.atomic.AtomicReference

import akka.actor.typed.scaladsl.{ActorContext, Behaviors}
import akka.actor.typed.{ActorRef, Behavior, DispatcherSelector}

import naogateway.gateway.link.{Backlog, Relay, Replay, ReplayLink, RobotLink, RobotPort, UdpLink}
import naogateway.proto.RecordedPort
import naogateway.api.recording.Decision
import naogateway.gateway.recording.{Recording, RobotClockEstimates}
import naogateway.gateway.tap.Tap
import naogateway.access.GatewayAccess
import naogateway.api.{GatewayAddresses, GatewayEvent, RobotStatusUpdated}
import naogateway.gateway.link.PortReader
import naogateway.gateway.robot.{Outbox, RobotActor, RobotRef}

/** The robot side of the middleware: the robots' UDP port, the robot registry, the GameController and the relay. */
object Gateway {

  /** What the gateway takes besides its public protocol ([[GatewayAccess]]): its own parts' messages, and the public
    * protocol's, each wrapped into [[AccessRequest]] as it arrives. Only the gateway's package sends these.
    */
  private[naogateway] sealed trait Command

  /** A message of the public protocol, as the gateway takes it. */
  private[naogateway] final case class AccessRequest(request: GatewayAccess.Command) extends Command

  /** Answers with the robot actor of `robotId`, if the robot is known (the gateway's own specs, through its test kit).
    */
  private[naogateway] final case class GetRobot(robotId: Int, replyTo: ActorRef[Option[ActorRef[RobotActor.Command]]])
      extends Command

  private[naogateway] final case class GameControllerEvent(event: UdpLink.Event) extends Command
  private[naogateway] final case class TeamMessageEvent(event: UdpLink.Event) extends Command
  private[naogateway] final case class MonitorStatusEvent(event: UdpLink.Event) extends Command
  private[naogateway] final case class Unrouted(frame: Routing.ToGateway) extends Command
  private[naogateway] final case class SubscriberGone(subscriber: ActorRef[GatewayEvent]) extends Command
  private[naogateway] final case class RobotStopped(robotId: Int, actor: ActorRef[RobotActor.Command]) extends Command
  private[naogateway] final case class RobotWantsSubscribers(request: RobotActor.SubscribersWanted) extends Command

  /** Where the robot actors, their children and the outbox run (`naogateway.dispatcher`). */
  val RobotDispatcher: DispatcherSelector = DispatcherSelector.fromConfig("naogateway.dispatcher")

  /** A known robot: `address` is where it receives (its IP at its receive port), and its IP is who it is; with
    * `signatures`, its frames count only when signed (the IP alone does not identify it then). A `discovered` one was
    * introduced by its keep-alive: it counts against `discovery.max-robots` and may be forgotten.
    */
  private[naogateway] final case class Entry(actor: RobotRef, address: InetSocketAddress, zeromq: Boolean,
      backlog: Backlog,
      signatures: Option[SignatureCheck] = None, discovered: Boolean = false)

  /** The gateway with `configured` settings, on its sockets; or, with `replay`, fed from a recording instead: no socket
    * is opened, nothing is sent anywhere, nothing is recorded. Whoever spawns it holds it as its public protocol; each
    * message of that is wrapped into [[AccessRequest]] in the gateway's own mailbox, and the gateway's own parts'
    * messages (not of that protocol) pass the wrapping untouched.
    */
  def apply(configured: GatewaySettings, replay: Option[Replay] = None): Behavior[GatewayAccess.Command] =
    Behaviors.setup[Command](context => start(configured, replay, context)).transformMessages[GatewayAccess.Command] {
      case request => AccessRequest(request)
    }

  private def start(
      configured: GatewaySettings, replay: Option[Replay], context: ActorContext[Command]): Behavior[Command] = {
    // A replay reaches no robot: ZeroMQ robots, which would be called over their own sockets, are left out.
    val settings =
      if (replay.isEmpty) configured else configured.copy(zeromq = configured.zeromq.copy(robots = Vector.empty))
    Behaviors.withStash(1024) { stash =>
      val bind = new InetSocketAddress(settings.bindAddress, settings.robotPort)
      val port: RobotLink = replay match {
        case Some(r) =>
          context.log.info("Gateway replaying {} at {}x: nothing is sent", r.files.mkString(", "), r.speed)
          new ReplayLink(r, s"${context.system.name}-replay")
        case None =>
          val p =
            try RobotPort.open(bind, ReceiveBufferBytes, s"${context.system.name}-robot-port")
            catch {
              case e: java.io.IOException =>
                throw new IllegalStateException(s"gateway cannot listen for robots on $bind: $e", e)
            }
          context.log.info("Gateway listening for robots on {}", p.localAddress)
          p
      }
      val clocks = new RobotClockEstimates
      val routes = new AtomicReference[Routing.Table[PortReader.Inlet]](Routing.Table.empty)
      // What crosses the ports, for every reader: the recorder, the live feed, the FU-Remote relay.
      val tap = new Tap
      val recording =
        if (replay.isDefined) Recording.Off
        else Recording(settings.recording, s"${context.system.name}-recorder", tap, clocks)
      val relay = settings.relay.filter(_ => replay.isEmpty).map(to =>
        new Relay(PortReader.tapped(port, tap, RecordedPort.FU_REMOTE_RELAY, port.localAddress, routes), to, tap,
          Relay.Capacity, s"${context.system.name}-relay"))
      // One for the gateway's life: the robots' replay windows and epochs, and timestamps that keep growing across
      // restarts of the outbox and the robot actors.
      val signer = settings.signingKey.map(new GatewaySigning(_))
      val outbox = context.spawn(
        Behaviors.supervise(Outbox(PortReader.tapped(port, tap, RecordedPort.ROBOT_PORT, port.localAddress, routes),
            settings.budget, settings.competition, signer, tap))
          .onFailure(settings.supervision.outbox.strategy),
        "outbox",
        RobotDispatcher
      )
      val logic =
        new GatewayLogic(settings, context, stash, port, outbox, tap, recording, relay, routes, clocks, signer)
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
          UdpLink(
            new InetSocketAddress(settings.gameControllerBindAddress, settings.teamMessages.port),
            teamEvents,
            UdpLink.Options(reuseAddress = true, broadcast = true,
              maxDatagramsPerSecond = settings.teamMessages.maxDatagramsPerSecond)
          ),
          "team-message-link"
        )
      }
      if (settings.gameControllerEnabled && replay.isEmpty) {
        context.spawn(
          UdpLink(
            new InetSocketAddress(settings.gameControllerBindAddress, settings.gameControllerPort),
            context.messageAdapter(GameControllerEvent.apply),
            UdpLink.Options(
              reuseAddress = settings.gameControllerReuseAddress,
              broadcast = true,
              maxDatagramsPerSecond = settings.gameControllerMaxDatagramsPerSecond,
              // Trust before the cap (docs/protocol.md 10.7): a stranger's flood cannot crowd out the GameController.
              trusted = a => settings.gameControllerTrusted.configured && settings.gameControllerTrusted.trusts(a)
            )
          ),
          "game-controller-link"
        )
        logic.bindingGameController
      } else stash.unstashAll(logic.running(GatewayAddresses(port.localAddress, None)))
    }
  }

  /** While recording: hands the gateway's events to the tap as decisions. The robot actors send it no keep-alive's
    * status (on the recording's status channels already; the clock estimate with which the recorder dates the robot's
    * Status is in [[RobotClockEstimates]]), but one held while they waited for their subscribers may come: ignored.
    */
  private[naogateway] def recordingEvents(tap: Tap): Behavior[GatewayEvent] =
    Behaviors.receiveMessage {
      case _: RobotStatusUpdated =>
        Behaviors.same
      case event =>
        tap.decision(Decision.Published(event))
        Behaviors.same
    }

  /** The kernel receive buffer of the robot port: a burst of a few thousand datagrams waits there, not dropped. */
  private val ReceiveBufferBytes = 4 * 1024 * 1024
}
