package naogateway.gateway.link

import java.net.InetSocketAddress
import java.util.concurrent.atomic.AtomicReference

import akka.actor.typed.ActorRef

import naogateway.transport.DatagramWriter
import naogateway.proto.RecordedPort
import naogateway.gateway.tap.Tap
import naogateway.gateway.{Gateway, Rejection, RejectionLedger, Routing, SignatureCheck}
import naogateway.gateway.robot.{Outbox, RobotActor}

/** The robot port's reader side of the gateway: runs where the port is read (the robot dispatcher's port loop, or a
  * reader thread), routes each datagram with the table the gateway last published, and hands the robot actors (or the
  * gateway) their messages directly.
  */
private[naogateway] final class PortReader(
    port: RobotLink,
    gateway: ActorRef[Gateway.Command],
    gatewayBacklog: Backlog,
    outbox: ActorRef[Outbox.Command],
    rejections: RejectionLedger.Shared,
    tap: Tap,
    val routes: AtomicReference[Routing.Table[PortReader.Inlet]],
    progress: PortProgress
) extends RobotPort.Handler {
  import PortReader._

  // Written by the one thread that reads the port; read by the gateway for its figures.
  @volatile var datagramsIn = 0L
  // What the outbox has not been told yet: told in one message per InboundBatch datagrams or when the port is quiet.
  private var inboundDatagrams, inboundBytes = 0

  def received(bytes: Array[Byte], from: InetSocketAddress): Unit = {
    datagramsIn += 1
    progress.reading()
    val table = routes.get
    inboundDatagrams += 1
    inboundBytes += bytes.length
    if (inboundDatagrams >= InboundBatch) flushInbound()
    val decision = Routing.decide(table, bytes, from)
    // A robot that must sign: nothing acts on its frame before the signature and the replay window pass.
    // (A match, not a map: a map's function would be built for every frame.)
    val refused = decision match {
      case Routing.ToRobot(route, header, _, _) =>
        route.target.signatures match {
          case Some(check) => check.check(bytes, header).left.toOption
          case None        => None
        }
      case _ => None
    }
    // The recorder, the live feed and the FU-Remote relay read it from the tap, off this thread, published before
    // anything acts on it (so it comes before the decisions it leads to).
    if (tap.listening) tapped(table, decision, refused.isEmpty, bytes, from)
    decision match {
      case Routing.ToRobot(route, header, contents, size) =>
        refused match {
          case Some(kind) =>
            rejections.count(kind, from)
            if (route.target.backlog.tryAdd()) route.target.actor ! RobotActor.DatagramRejected(kind)
          case None => deliver(route, RobotActor.FrameReceived(contents, header.form, size), from)
        }
      case Routing.SegmentToRobot(route, segment) =>
        deliver(route, RobotActor.SegmentReceived(segment), from)
      case unrouted: Routing.ToGateway =>
        if (gatewayBacklog.tryAdd()) gateway ! Gateway.Unrouted(unrouted)
        else rejections.count(Rejection.GatewayBusy, from)
      case Routing.Rejected(kind, detail, route) =>
        rejections.count(kind, from, detail)
        route.foreach(r => if (r.target.backlog.tryAdd()) r.target.actor ! RobotActor.DatagramRejected(kind))
    }
  }

  /** The datagram as the tap publishes it, with its frame decoded only where it is a known robot's own: from the
    * robot's bound address and, for a robot that signs, past its signature check. Anything else (another address in a
    * robot's name, a forged or replayed signature, a frame the gateway has yet to judge for discovery) reaches readers
    * as raw bytes only, so no reader shows it on a robot's channels.
    */
  private def tapped(table: Routing.Table[Inlet], decision: Routing.Decision[Inlet], accepted: Boolean,
      bytes: Array[Byte], from: InetSocketAddress): Unit =
    decision match {
      case Routing.ToRobot(route, _, contents, _) =>
        tap.datagram(RecordedPort.ROBOT_PORT, received = true, from, port.localAddress, bytes, route.robotId,
          if (accepted) Some(contents) else None)
      case _ =>
        tap.datagram(RecordedPort.ROBOT_PORT, received = true, from, port.localAddress, bytes,
          table.byAddress.get(from.getAddress).fold(-1)(_.robotId))
    }

  private def deliver(route: Routing.Route[Inlet], message: RobotActor.Command, from: InetSocketAddress): Unit =
    if (route.target.backlog.tryAdd()) route.target.actor ! message else rejections.count(Rejection.RobotBusy, from)

  def caughtUp(): Unit = {
    progress.caughtUp()
    flushInbound()
  }

  // The outbox's figures of what came in, in batches.
  private def flushInbound(): Unit =
    if (inboundDatagrams > 0) {
      outbox ! Outbox.Inbound(inboundDatagrams, inboundBytes)
      inboundDatagrams = 0
      inboundBytes = 0
    }

  def gameControllerReceived(bytes: Array[Byte], from: InetSocketAddress): Unit =
    gateway ! Gateway.GameControllerEvent(UdpLink.Received(bytes, from))
}

/** What the reader routes to, and the tap's view of what the gateway's links send. */
private[naogateway] object PortReader {

  /** Received datagrams the port's reader counts before it tells the outbox (one message, not one per datagram). */
  val InboundBatch: Int = 64

  /** A datagram robot as the port's reader reaches it: its actor, the backlog of what the reader handed it, and for a
    * robot that must sign, the check every frame passes before it is handed on.
    */
  final case class Inlet(actor: ActorRef[RobotActor.Command], backlog: Backlog, signatures: Option[SignatureCheck])

  /** `link`, with every datagram it takes published on `tap` as sent from `local` on `port` (while anyone listens).
    */
  def tapped(link: DatagramWriter, tap: Tap, port: RecordedPort, local: InetSocketAddress,
      routes: AtomicReference[Routing.Table[Inlet]]): DatagramWriter =
    new DatagramWriter {
      def send(bytes: Array[Byte], to: InetSocketAddress): Boolean = {
        val sent = link.send(bytes, to)
        if (sent && tap.listening)
          tap.datagram(port, received = false, local, to, bytes,
            routes.get.byAddress.get(to.getAddress).fold(-1)(_.robotId))
        sent
      }
    }
}
