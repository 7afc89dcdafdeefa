package apps.datagram

import java.net.InetSocketAddress
import java.util.concurrent.atomic.AtomicLong

import scala.concurrent.Promise
import scala.util.{Failure, Success, Try}

import akka.actor.CoordinatedShutdown
import akka.actor.typed.scaladsl.{ActorContext, Behaviors}
import akka.actor.typed.{ActorRef, Behavior, DispatcherSelector, PostStop}

import apps.zeromq.{EndpointProtocol, EndpointRequest, Registering, RequestDesk}
import naogateway.transport.RateLimitedLog
import naogateway.transport.DatagramPort
import robotmiddleware.{RobotInterface, RobotMiddleware}

/** The RobotInterface for programs on the same machine at the lowest latency: each request one UDP datagram, the same
  * serialized `Message` with an `rpcRequest` the ZeroMQ endpoint takes, each reply one datagram to the sender's address
  * and port, carrying the request's `callId` (docs/zeromq.md, "The datagram door"). No I/O thread between the socket
  * and the door: the socket is a [[DatagramPort]] read on the thread of the dispatcher `apps.datagram-door.dispatcher`
  * names when that runs on a port loop (the launcher names the gateway's robot dispatcher: a request then runs through
  * the middleware to the robot on the thread it woke), or by a reader thread of its own otherwise. That thread parses
  * and hands each request on (`RequestDesk`, shared with the ZeroMQ endpoint), and a reply leaves from the thread that
  * has the answer. Calls only: streams and subscriptions stay with the ZeroMQ endpoint.
  *
  * Everything is bounded: a datagram longer than `max-datagram-bytes`, one that is not a request, and one beyond the
  * requests in flight (in all, or from its sender) is dropped without a reply, counted by kind (`Drop`) and logged at
  * the 1st, 10th, 100th, ... of its kind. This actor owns the socket and the reader: it binds, starts, and on stop (or
  * early in a coordinated shutdown) answers what is pending and closes the socket, which ends the reader.
  */
object DatagramDoor {

  /** What the door accepts. */
  sealed trait Command

  /** Answers with the bound address (the real port when 0 was configured). */
  final case class GetAddress(replyTo: ActorRef[InetSocketAddress]) extends Command

  /** Answers with the door's figures. */
  final case class GetStats(replyTo: ActorRef[Stats]) extends Command

  /** Requests handed on, and datagrams dropped by kind (every kind listed, zero or not). */
  final case class Stats(accepted: Long, dropped: Map[Drop, Long])

  /** Why a datagram was dropped. */
  sealed abstract class Drop(val name: String) extends Product with Serializable

  /** The kinds of drops. */
  object Drop {

    /** Longer than `max-datagram-bytes`. */
    case object Oversize extends Drop("oversize")

    /** Not a `Message` with a complete `rpcRequest`. */
    case object Unreadable extends Drop("unreadable")

    /** `max-in-flight` requests were in progress. */
    case object Overloaded extends Drop("overloaded")

    /** `max-in-flight-per-sender` requests of its sender were in progress. */
    case object SenderOverloaded extends Drop("sender-overloaded")

    /** A reply the socket would not take (its buffer full, or the socket closed). */
    case object ReplyNotSent extends Drop("reply-not-sent")

    /** Every kind. */
    val all: Vector[Drop] = Vector(Oversize, Unreadable, Overloaded, SenderOverloaded, ReplyNotSent)
  }

  /** The reader thread's name suffix (tests look for it to see that the thread has ended). */
  val ReaderName: String = "datagram-door"

  private final case class Registered(result: Try[RobotInterface]) extends Command
  private case object SocketClosed extends Command

  /** The door for `middleware`'s robots: it registers as app `settings.appName` and ends that session when it stops. */
  def apply(middleware: ActorRef[RobotMiddleware.Command], settings: DatagramDoorSettings): Behavior[Command] =
    Registering[Command](middleware, settings.appName, settings.priority, "datagram door")(Registered,
      { case Registered(r) => r })(
      serving(_, settings, ownsInterface = true))

  /** Spawns the door as a child of `context` when `apps.datagram-door.enabled` opens it ([[apps.Doors.open]]: `auto`
    * keeps it shut while `realRobots`) and its bind address is loopback; a refused door is logged, not started.
    */
  def spawnIfEnabled(context: ActorContext[_], middleware: ActorRef[RobotMiddleware.Command],
      realRobots: Boolean): Option[ActorRef[Command]] = {
    val settings = DatagramDoorSettings(context.system)
    if (!apps.Doors.open(settings.enabled, realRobots)) None
    else settings.refusal match {
      case Some(reason) =>
        context.log.error("Datagram door not started: {}", reason)
        None
      case None => Some(context.spawn(apply(middleware, settings), "datagram-door"))
    }
  }

  /** The door in front of `robots`, which the caller owns (and closes). */
  def withInterface(robots: RobotInterface, settings: DatagramDoorSettings): Behavior[Command] =
    serving(robots, settings, ownsInterface = false)

  private def serving(
      robots: RobotInterface, settings: DatagramDoorSettings, ownsInterface: Boolean): Behavior[Command] =
    Behaviors.setup { context =>
      Try {
        settings.refusal.foreach(r => throw new IllegalArgumentException(r))
        open(settings, s"${context.system.name}-$ReaderName")
      } match {
        case Failure(e) =>
          context.log.error("datagram door cannot bind {}:{}: {}", settings.bindAddress, settings.port, e.toString)
          if (ownsInterface) robots.close()
          Behaviors.stopped
        case Success(port) =>
          val door = new Door(robots, settings, port, context)
          context.pipeToSelf(door.ended)(_ => SocketClosed)
          val unbind = CoordinatedShutdown(context.system)
            .addCancellableTask(CoordinatedShutdown.PhaseServiceUnbind, s"$ReaderName-close") { () =>
              door.close()
              scala.concurrent.Future.successful(akka.Done)
            }
          door.start(context.system.dispatchers.lookup(DispatcherSelector.fromConfig(settings.dispatcher)))
          val address = port.localAddress
          context.log.info("datagram door serving requests on {}", address)
          def stop(): Unit = {
            door.close()
            unbind.cancel()
            if (ownsInterface) robots.close()
            context.log.info("datagram door stopped")
          }
          Behaviors.receiveMessage[Command] {
            case GetAddress(replyTo) =>
              replyTo ! address
              Behaviors.same
            case GetStats(replyTo) =>
              replyTo ! door.stats
              Behaviors.same
            case SocketClosed =>
              context.log.info("datagram door: the socket closed; the door stops")
              Behaviors.stopped
            case Registered(_) => Behaviors.unhandled
          }.receiveSignal { case (_, PostStop) =>
            stop()
            Behaviors.same
          }
      }
    }

  /** The kernel receive buffer of the door's socket: a burst of requests waits there, not dropped. */
  private val ReceiveBufferBytes = 1024 * 1024

  private def open(settings: DatagramDoorSettings, readerName: String): DatagramPort =
    DatagramPort.open(new InetSocketAddress(settings.bindAddress, settings.port), ReceiveBufferBytes, readerName)

  /** The socket, the counters and the desk. The desk's state is guarded by the desk's lock, which the reading thread
    * takes for each request and an answer's thread for its reply; nothing waits while holding it (the socket does not
    * block).
    */
  private final class Door(
      robots: RobotInterface,
      settings: DatagramDoorSettings,
      port: DatagramPort,
      context: ActorContext[Command]
  ) extends DatagramPort.Handler {
    private val log = org.slf4j.LoggerFactory.getLogger(classOf[Door])
    private val accepted = new AtomicLong
    private val drops: Map[Drop, AtomicLong] = Drop.all.map(_ -> new AtomicLong).toMap
    private val finished = Promise[Unit]()
    @volatile private var open = true
    private val lock = new Object
    private val desk = new RequestDesk[InetSocketAddress](
      robots,
      "datagram door",
      settings.requestTimeout,
      operation => lock.synchronized(operation()),
      (to, reply) => send(to, reply),
      context.executionContext,
      context.system.scheduler,
      robotmiddleware.MiddlewareSettings(context.system).servoLimits
    )

    /** Completes when the socket has closed. */
    def ended: scala.concurrent.Future[Unit] = finished.future

    /** Reads the socket on `executor`'s port loop, or with a reader thread of its own. */
    def start(executor: java.util.concurrent.Executor): Unit = port.startOn(this, executor)

    def stats: Stats = Stats(accepted.get, drops.map { case (k, v) => k -> v.get })

    /** Answers the requests in progress, then closes the socket; the reader ends. Safe to call more than once. */
    def close(): Unit = {
      val wasOpen = lock.synchronized {
        val was = open
        if (was) {
          desk.shutDown()
          open = false
        }
        was
      }
      if (wasOpen) {
        Try(port.close(2000L))
        finished.trySuccess(())
      }
      ()
    }

    def received(bytes: Array[Byte], from: InetSocketAddress): Unit =
      if (bytes.length > settings.maxDatagramBytes) dropped(Drop.Oversize, from)
      else {
        EndpointProtocol.parse(bytes) match {
          case Left(_)        => dropped(Drop.Unreadable, from)
          case Right(request) => take(request, from)
        }
      }

    private def take(request: EndpointRequest, from: InetSocketAddress): Unit = {
      val refused = lock.synchronized {
        if (!open) None
        else if (desk.inFlight >= settings.maxInFlight) Some(Drop.Overloaded)
        else if (desk.inFlightOf(from) >= settings.maxInFlightPerSender) Some(Drop.SenderOverloaded)
        else {
          accepted.incrementAndGet()
          desk.accept(from, request)
          None
        }
      }
      refused.foreach(dropped(_, from))
    }

    def caughtUp(): Unit = ()

    private def send(to: InetSocketAddress, reply: Array[Byte]): Unit =
      if (!port.send(reply, to)) dropped(Drop.ReplyNotSent, to)

    private def dropped(kind: Drop, from: InetSocketAddress): Unit = {
      val n = drops(kind).incrementAndGet()
      if (RateLimitedLog.due(n))
        log.warn("datagram door: {} datagram dropped from {} ({} of this kind so far)", kind.name,
          from, n)
    }
  }
}
