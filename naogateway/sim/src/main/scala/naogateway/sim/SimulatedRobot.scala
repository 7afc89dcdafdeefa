package naogateway.sim

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.Done
import akka.actor.typed.scaladsl.{ActorContext, Behaviors, StashBuffer, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior}

import naogateway.gateway.link.UdpLink

/** One simulated CM-530 robot on real UDP sockets: [[RobotFirmware]] in real time, behind the GS1500M and CM-530 models
  * ([[FaithfulLink]]) or straight on the sockets.
  *
  * Two sockets, as the thesis hardware has: the GS1500M keeps a UDP client connection for everything it sends and a UDP
  * server on port 3838 for everything it receives. So the robot sends from one socket (its IP, a port of the system's
  * choosing) and receives on another (its IP, the receive port); a datagram sent to the source port of its datagrams
  * reaches the sending socket, is counted and is not acted on, exactly as a gateway that answered to the source port
  * would find with a real robot. [[SimulatedRobot.Reconnect]] gives the sending socket a new port, as a module
  * reconnect does.
  *
  * The robot sends keep-alives and debug output to the configured gateway address and answers each request to its
  * sender. Time is `System.nanoTime` relative to the robot's start; the pure models run in that clock, and the actor
  * wakes up with one keyed timer at the earliest moment any of them has something to do. Timers fire on the scheduler's
  * tick (10 ms by default), so a datagram may leave up to one tick after the model put it on air; the models' own time
  * order is unaffected, because every wake-up first catches them up to the present.
  */
object SimulatedRobot {

  /** The GS1500M needs about 4 s after power-up before it answers (docs/protocol.md §12). */
  val ModuleBootDelay: FiniteDuration = 4.seconds

  /** Where a robot receives on its own IP address (docs/protocol.md section 2). */
  val ReceivePort: Int = 3838

  /** What a simulated robot accepts. */
  sealed trait Command

  /** Asks for a snapshot of the robot. */
  final case class GetState(replyTo: ActorRef[RobotView]) extends Command

  /** Asks for the receive log: the calls the firmware has read, oldest first (the latest `ReceiveLogCapacity`). */
  final case class GetReceivedCalls(replyTo: ActorRef[Vector[ReceivedCall]]) extends Command

  /** Calls the receive log keeps; older ones are forgotten. */
  val ReceiveLogCapacity: Int = 20000

  /** Cuts the power: the robot falls silent at once, its firmware restarts (new boot id, uptime from now, debug options
    * off, fresh stream), and its module answers again after `bootDelay`.
    */
  final case class PowerCycle(bootDelay: FiniteDuration = ModuleBootDelay) extends Command

  /** Sets the battery voltage (e.g. an empty battery for a safety test). */
  final case class SetBattery(volts: Double) extends Command

  /** Moves the ball to field coordinates (metres); the camera sees the new scene from the next frame on. */
  final case class MoveBall(x: Double, y: Double) extends Command

  /** Closes the robot's sockets and stops the robot; `Done` once both ports are free. */
  final case class Stop(replyTo: ActorRef[Done]) extends Command

  /** The module reconnects its client connection: the robot sends from a new port from now on (it keeps receiving where
    * it did); `replyTo` learns the new source address.
    */
  final case class Reconnect(replyTo: ActorRef[InetSocketAddress]) extends Command

  private[sim] case object WakeUp extends Command
  private[sim] case object ModuleUp extends Command
  private[sim] case object StopTimedOut extends Command
  private[sim] final case class SocketGone(link: ActorRef[UdpLink.Command]) extends Command
  // Events of the receive socket (FromSocket) and of the sending socket (FromSender), told apart by adapter.
  private[sim] final case class FromSocket(event: UdpLink.Event) extends Command
  private[sim] final case class FromSender(event: UdpLink.Event) extends Command

  /** What a robot reports once its socket is bound, or could not be. */
  sealed trait StartResult

  /** The robot is running and receives at `address` (its IP at the receive port). */
  final case class Started(robotId: Int, robot: ActorRef[Command], address: InetSocketAddress) extends StartResult

  /** A socket could not be bound; the robot has stopped. */
  final case class StartFailed(robotId: Int, reason: String) extends StartResult

  private[sim] case object WakeUpKey
  private[sim] case object ModuleUpKey
  private[sim] case object StopKey

  // Commands that arrive before the socket is bound wait; more than this many means something is wrong.
  private val StashCapacity = 1000
  private[sim] val StopTimeout = 5.seconds
  private[sim] val MinStreamTickNanos = 1000000L
  private[sim] val MaxRounds = 8

  /** A robot with `settings`; `reportTo` learns its receive address (or the failure). */
  def apply(settings: SimulatedRobotSettings, reportTo: Option[ActorRef[StartResult]] = None): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        Behaviors.withStash(StashCapacity) { stash =>
          val id = settings.firmware.robotId
          val host = settings.bindAddress.getAddress
          val fromSocket = context.messageAdapter[UdpLink.Event](FromSocket.apply)
          // Akka keeps one message adapter per message class, so the sending socket's events come through a relay.
          val self = context.self
          val fromSender = context.spawn(Behaviors.receiveMessage[UdpLink.Event] { event =>
              self ! FromSender(event)
              Behaviors.same
            }, "sending-socket-events")
          // The receive socket shares its port with a GameController listener on the same host (the demo binds
          // 0.0.0.0:3838 with SO_REUSEADDR); the more specific address still gets the robot's unicast datagrams.
          val receiveOptions = UdpLink.Options(reuseAddress = true, receiveBufferBytes = settings.receiveBufferBytes)
          val receiver =
            context.spawn(UdpLink(new InetSocketAddress(host, settings.receivePort), fromSocket, receiveOptions),
              "udp-receive")
          val sender =
            context.spawn(UdpLink(settings.bindAddress, fromSender, UdpLink.Options(receiveBufferBytes = 64 * 1024)),
              "udp-send")
          context.watchWith(receiver, SocketGone(receiver))
          context.watchWith(sender, SocketGone(sender))
          val origin = System.nanoTime()

          def binding(received: Option[InetSocketAddress], sending: Option[InetSocketAddress]): Behavior[Command] =
            (received, sending) match {
              case (Some(local), Some(from)) =>
                context.log.debug("Simulated robot [{}] receives on {} and sends from {}", id, local, from)
                reportTo.foreach(_ ! Started(id, context.self, local))
                val robot =
                  new SimulatedRobotRun(settings, context, timers, receiver, local, sender, from, fromSender, origin)
                stash.unstashAll(robot.start())
              case _ =>
                Behaviors.receiveMessage {
                  case FromSocket(UdpLink.Bound(_, local))             => binding(Some(local), sending)
                  case FromSender(UdpLink.Bound(_, local))             => binding(received, Some(local))
                  case FromSocket(UdpLink.BindFailed(address, reason)) => failed(address, reason)
                  case FromSender(UdpLink.BindFailed(address, reason)) => failed(address, reason)
                  case FromSocket(UdpLink.Received(_, _)) | FromSender(UdpLink.Received(_, _)) =>
                    Behaviors.same
                  case SocketGone(_) =>
                    reportTo.foreach(_ ! StartFailed(id, "a socket stopped before it was bound"))
                    Behaviors.stopped
                  case Stop(replyTo) =>
                    receiver ! UdpLink.Unbind
                    sender ! UdpLink.Unbind
                    stoppingWithoutSocket(id, Set(receiver, sender), Vector(replyTo), timers, context)
                  case other =>
                    stashOrDrop(stash, other, context, id)
                }
            }

          def failed(address: InetSocketAddress, reason: String): Behavior[Command] = {
            context.log.warn("Simulated robot [{}] cannot bind {}: {}", id, address, reason)
            reportTo.foreach(_ ! StartFailed(id, s"$address: $reason"))
            Behaviors.stopped
          }

          binding(None, None)
        }
      }
    }

  // Stop before the sockets were bound: the links stop at once, taking their half-open sockets with them.
  private def stoppingWithoutSocket(
      id: Int,
      links: Set[ActorRef[UdpLink.Command]],
      waiting: Vector[ActorRef[Done]],
      timers: TimerScheduler[Command],
      context: ActorContext[Command]
  ): Behavior[Command] = {
    timers.startSingleTimer(StopKey, StopTimedOut, StopTimeout)
    Behaviors.receiveMessage {
      case SocketGone(link) if links.size > 1 => stoppingWithoutSocket(id, links - link, waiting, timers, context)
      case SocketGone(_) | StopTimedOut =>
        context.log.debug("Simulated robot [{}] stopped before it was bound", id)
        waiting.foreach(_ ! Done)
        Behaviors.stopped
      case Stop(replyTo) => stoppingWithoutSocket(id, links, waiting :+ replyTo, timers, context)
      case GetState(_) | GetReceivedCalls(_) | PowerCycle(_) | SetBattery(_) | MoveBall(_, _) | WakeUp | ModuleUp |
          FromSocket(_) | FromSender(_) | Reconnect(_) =>
        Behaviors.same
    }
  }

  private def stashOrDrop(
      stash: StashBuffer[Command],
      command: Command,
      context: ActorContext[Command],
      id: Int
  ): Behavior[Command] = {
    if (stash.isFull) context.log.warn("Simulated robot [{}] dropped {} while binding its socket", id, command)
    else stash.stash(command)
    Behaviors.same
  }

  /** The robot's route back to a request that came through the secure stream. */
  private[sim] val ThroughStream: InetSocketAddress = InetSocketAddress.createUnresolved("secure-stream", 0)

  private[sim] final case class Out(bytes: Array[Byte], to: InetSocketAddress)

  /** Everything that changes while the robot runs. `armedAt` is the wake-up timer's target (`Long.MinValue`: none). */
  private[sim] final case class Robot(
      firmware: FirmwareState,
      link: Option[FaithfulLink],
      stream: Option[RobotStream],
      stats: RobotStats,
      armedAt: Long
  )
}
