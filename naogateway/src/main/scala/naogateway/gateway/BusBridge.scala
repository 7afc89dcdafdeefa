package naogateway.gateway

import java.net.InetSocketAddress

import scala.concurrent.Future
import scala.concurrent.duration._
import scala.util.{Failure, Success}

import akka.Done
import akka.actor.typed.scaladsl.AskPattern._
import akka.actor.typed.scaladsl.{ActorContext, Behaviors}
import akka.actor.typed.{ActorRef, Behavior}
import akka.stream.scaladsl.{Flow, Keep, Sink, Source, Tcp}
import akka.stream.{KillSwitches, UniqueKillSwitch}
import akka.util.{ByteString, Timeout}

import com.google.protobuf.{ByteString => ProtoBytes}

import naogateway.proto.BusBridge
import naogateway.wire.{BusBridgeFrame, Dynamixel}
import naogateway.access.GatewayAccess
import naogateway.api.{
  BusBridgeClient,
  GatewayEvent,
  RobotForgotten,
  RobotOffline,
  RobotOnline,
  RobotSnapshot,
  TrafficStats
}
import naogateway.gateway.robot.{RobotActor, RobotEffects, StreamActor}
import naogateway.transport.RateLimitedLog
import naogateway.gateway.gamecontroller.CompetitionGate

/** The gateway's bus bridge (docs/protocol.md 6.9): one TCP listener on loopback per online robot, at `base-port` +
  * robot id, while the competition gate's reading says the game does not run (in competition mode or not). It follows
  * the robots' comings and goings (the gateway's events) and the gate (the outbox's figures, asked every
  * [[BusBridgeServer.GatePoll]]); a robot going offline or the gate closing closes its listener and its client.
  */
object BusBridgeServer {

  /** What the bridge takes. */
  sealed trait Command

  private final case class Event(event: GatewayEvent) extends Command
  private final case class Gate(traffic: TrafficStats) extends Command
  private final case class Listed(robots: Vector[RobotSnapshot]) extends Command
  private case object PollGate extends Command
  private case object PollKey

  /** How often the bridge asks the outbox whether the gate is open. */
  val GatePoll: FiniteDuration = 200.millis

  /** The bridge over `gateway` with `settings`; `leases` learns when a tool connects to a robot's bridge and leaves. */
  def apply(gateway: ActorRef[GatewayAccess.Command], settings: BusBridgeSettings,
      leases: Option[ActorRef[BusBridgeClient]]): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        gateway ! GatewayAccess.Subscribe(context.messageAdapter(Event.apply))
        gateway ! GatewayAccess.GetRobots(context.messageAdapter(Listed.apply))
        val gate = context.messageAdapter(Gate.apply)
        timers.startTimerWithFixedDelay(PollKey, PollGate, GatePoll)
        gateway ! GatewayAccess.GetTraffic(gate)

        def sync(online: Set[Int], open: Boolean): Unit = {
          val wanted = if (open) online else Set.empty[Int]
          context.children.foreach { child =>
            val id = child.path.name.stripPrefix("robot-").toIntOption
            if (!id.exists(wanted)) context.stop(child)
          }
          wanted.foreach { id =>
            val name = s"robot-$id"
            if (context.child(name).isEmpty)
              settings.portOf(id).foreach(port =>
                context.spawn(BusBridgePort(id, new InetSocketAddress(settings.bindAddress, port), gateway, settings,
                    leases), name))
          }
        }

        def running(online: Set[Int], open: Boolean): Behavior[Command] = Behaviors.receiveMessage {
          case Event(RobotOnline(id, _)) =>
            sync(online + id, open); running(online + id, open)
          case Event(RobotOffline(id, _)) =>
            sync(online - id, open); running(online - id, open)
          case Event(RobotForgotten(id, _)) =>
            sync(online - id, open); running(online - id, open)
          case Event(_) => Behaviors.same
          case Listed(robots) =>
            val now = online ++ robots.filter(_.online).map(_.robotId)
            sync(now, open); running(now, open)
          case PollGate =>
            gateway ! GatewayAccess.GetTraffic(gate)
            Behaviors.same
          case Gate(traffic) =>
            // The gate's reading, whether or not competition mode holds back the rest of the traffic: a tool on the bus
            // moves the robot, which no team may do from the base station while the game runs (docs/protocol.md 6.9).
            val nowOpen = !traffic.gameRunning
            if (nowOpen != open)
              context.log.info("Bus bridge {}",
                if (nowOpen) "open again"
                else
                  s"closed: ${traffic.gateReason.getOrElse(CompetitionGate.NoSendingWhileGameRuns)}")
            sync(online, nowOpen); running(online, nowOpen)
        }
        // Closed until the outbox first says the gate is open.
        running(Set.empty, open = false)
      }
    }
}

/** One robot's bridge: its TCP listener, its one client, and the requests in flight through its secure stream. */
private[naogateway] object BusBridgePort {

  sealed trait Command
  private final case class Bound(binding: Tcp.ServerBinding) extends Command
  private final case class BindFailed(reason: Throwable) extends Command
  private final case class Incoming(connection: Tcp.IncomingConnection) extends Command
  private final case class ClientGone(client: Int) extends Command
  private final case class Stream(connected: Option[RobotEffects.Connected]) extends Command
  private final case class FromRobot(received: StreamActor.Received) extends Command
  private final case class Request(packet: Array[Byte], replyTo: ActorRef[ByteString]) extends Command
  private final case class Dropped(packets: Long) extends Command
  private final case class Expired(sequence: Long) extends Command

  private final case class Client(number: Int, kill: UniqueKillSwitch)

  /** Robot `robotId`'s bridge listening at `address`. */
  def apply(robotId: Int, address: InetSocketAddress, gateway: ActorRef[GatewayAccess.Command],
      settings: BusBridgeSettings, leases: Option[ActorRef[BusBridgeClient]]): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        implicit val system: akka.actor.typed.ActorSystem[Nothing] = context.system
        val self = context.self
        // A connection the listener accepts after this actor stopped (its unbind is under way) is closed at once, so
        // no tool waits on a connection nobody serves.
        val stopped = new java.util.concurrent.atomic.AtomicBoolean(false)
        val binding = Tcp(context.system).bind(address.getHostString, address.getPort)
          .to(Sink.foreach { c =>
            if (stopped.get) c.handleWith(Flow.fromSinkAndSource(Sink.cancelled[ByteString], Source.empty[ByteString]))
            else self ! Incoming(c)
          }).run()
        context.pipeToSelf(binding) {
          case Success(b) => Bound(b)
          case Failure(e) => BindFailed(e)
        }
        // The robot's secure stream carries the requests (docs/protocol.md 6.9).
        val own = gateway.unsafeUpcast[Any].narrow[Gateway.Command]
        context.pipeToSelf(own.ask[Option[ActorRef[RobotActor.Command]]](Gateway.GetRobot(robotId, _))(
            Timeout(5.seconds), context.system.scheduler).flatMap {
            case Some(robot) =>
              robot.ask[RobotEffects.Connected](RobotActor.Connect(_))(Timeout(10.seconds), context.system.scheduler)
                .map(Some(_))(context.executionContext)
            case None => Future.successful(None)
          }(context.executionContext)) {
          case Success(c) => Stream(c)
          case Failure(_) => Stream(None)
        }
        new BusBridgePort(robotId, settings, leases, binding, stopped, context, timers).waiting(None, Vector.empty)
      }
    }
}

private[naogateway] final class BusBridgePort(
    robotId: Int,
    settings: BusBridgeSettings,
    leases: Option[ActorRef[BusBridgeClient]],
    bound: Future[Tcp.ServerBinding],
    stopped: java.util.concurrent.atomic.AtomicBoolean,
    context: ActorContext[BusBridgePort.Command],
    timers: akka.actor.typed.scaladsl.TimerScheduler[BusBridgePort.Command]
) {
  import BusBridgePort._

  private implicit val system: akka.actor.typed.ActorSystem[Nothing] = context.system
  private var client = Option.empty[Client]
  private var clients = 0
  private var sequence = 0L
  private var pending = Option.empty[(Long, ActorRef[ByteString])]
  private var droppedPackets = 0L

  private def closeAll(): Unit = {
    stopped.set(true)
    client.foreach { c =>
      c.kill.shutdown()
      leases.foreach(_ ! BusBridgeClient(robotId, connected = false))
    }
    client = None
    pending.foreach(_._2 ! ByteString.empty)
    pending = None
    // A binding that completes after the stop is unbound too: the port is free for the next listener.
    bound.foreach(_.unbind())(context.system.executionContext)
  }

  private def common(message: Command): Option[Behavior[Command]] = message match {
    case Bound(b) =>
      context.log.info("Robot [{}]: bus bridge listens on {}", robotId, b.localAddress)
      Some(Behaviors.same)
    case BindFailed(e) =>
      context.log.warn("Robot [{}]: bus bridge cannot listen: {}", robotId, e.getMessage)
      Some(Behaviors.stopped)
    case Dropped(n) =>
      // Counted; logged at the 1st, 10th, 100th, ... so a tool sending garbage cannot flood the log.
      if (RateLimitedLog.dueBetween(droppedPackets, droppedPackets + n))
        context.log.warn("Robot [{}]: bus bridge dropped packets with a wrong length or checksum ({} so far)", robotId,
          droppedPackets + n)
      droppedPackets += n
      Some(Behaviors.same)
    case ClientGone(number) if client.exists(_.number == number) =>
      client = None
      pending.foreach(_._2 ! ByteString.empty)
      pending = None
      context.log.info("Robot [{}]: bus bridge client left", robotId)
      leases.foreach(_ ! BusBridgeClient(robotId, connected = false))
      Some(Behaviors.same)
    case ClientGone(_) => Some(Behaviors.same)
    case _             => None
  }

  // Until the robot's stream is known: a client may connect, its requests wait in the stream's order.
  def waiting(stream: Option[ActorRef[StreamActor.Command]], held: Vector[Request]): Behavior[Command] =
    Behaviors.receiveMessage[Command] { message =>
      common(message).getOrElse(message match {
        case Stream(Some(c)) =>
          c.stream ! StreamActor.Subscribe(context.messageAdapter(FromRobot.apply))
          held.foreach(context.self ! _)
          running(c.stream)
        case Stream(None) =>
          context.log.warn("Robot [{}]: bus bridge finds no secure stream; it closes", robotId)
          Behaviors.stopped
        case Incoming(connection) =>
          accept(connection); Behaviors.same
        case r: Request => waiting(stream, held :+ r)
        case _          => Behaviors.same
      })
    }.receiveSignal { case (_, akka.actor.typed.PostStop) => closeAll(); Behaviors.same }

  private def running(stream: ActorRef[StreamActor.Command]): Behavior[Command] =
    Behaviors.receiveMessage[Command] { message =>
      common(message).getOrElse(message match {
        case Incoming(connection) =>
          accept(connection); Behaviors.same
        case Request(packet, replyTo) =>
          sequence += 1
          val bridge = BusBridge(sequence.toInt, request = Some(ProtoBytes.copyFrom(packet)))
          BusBridgeFrame.encode(robotId, bridge) match {
            case Some(frame) =>
              pending = Some(sequence -> replyTo)
              stream ! StreamActor.Send(frame, Some(settings.requestTimeout))
              timers.startSingleTimer(Expired(sequence), settings.requestTimeout)
            case None => replyTo ! ByteString.empty
          }
          Behaviors.same
        case FromRobot(StreamActor.Received(_, payload)) =>
          BusBridgeFrame.decode(payload).foreach { case (_, reply) =>
            pending.filter(_._1.toInt == reply.sequence).foreach { case (s, replyTo) =>
              timers.cancel(Expired(s))
              replyTo ! reply.reply.fold(ByteString.empty)(b => ByteString(b.toByteArray))
              pending = None
            }
          }
          Behaviors.same
        case Expired(s) =>
          pending.filter(_._1 == s).foreach { case (_, replyTo) => replyTo ! ByteString.empty }
          if (pending.exists(_._1 == s)) pending = None
          Behaviors.same
        case _ => Behaviors.same
      })
    }.receiveSignal { case (_, akka.actor.typed.PostStop) => closeAll(); Behaviors.same }

  /** One tool at a time: a second connection is closed at once. */
  private def accept(connection: Tcp.IncomingConnection): Unit =
    if (client.isDefined) {
      context.log.info("Robot [{}]: bus bridge refuses {}: another tool holds it", robotId, connection.remoteAddress)
      connection.handleWith(Flow.fromSinkAndSource(Sink.cancelled[ByteString], Source.empty[ByteString]))
      ()
    } else {
      clients += 1
      val number = clients
      val self = context.self
      val timeout = Timeout(settings.requestTimeout * 2)
      // The stream runs off this actor: it takes what it needs of the context now.
      val scheduler = context.system.scheduler
      val ec = context.system.executionContext
      val flow = Flow[ByteString]
        .statefulMapConcat { () =>
          var reassembly = Dynamixel.Reassembly(maxPacketBytes = Dynamixel.MaxRequestBytes)
          bytes => {
            val (next, packets) = reassembly.feed(bytes.toArray)
            if (next.dropped > reassembly.dropped) self ! Dropped(next.dropped - reassembly.dropped)
            reassembly = next
            packets
          }
        }
        // One request in flight; replies go back in order.
        .mapAsync(1)(packet =>
          self.ask[ByteString](Request(packet, _))(timeout, scheduler).recover { case _ => ByteString.empty }(ec))
        .filter(_.nonEmpty)
        .viaMat(KillSwitches.single)(Keep.right)
        .watchTermination()(Keep.both)
      val (kill, done) = connection.handleWith(flow)
      context.pipeToSelf[Done](done)(_ => ClientGone(number))
      client = Some(Client(number, kill))
      context.log.info("Robot [{}]: bus bridge client {} connected", robotId, connection.remoteAddress)
      leases.foreach(_ ! BusBridgeClient(robotId, connected = true))
    }
}
