package apps.datagram

import java.io.IOException
import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.{ClosedChannelException, ClosedSelectorException, DatagramChannel, SelectionKey, Selector}
import java.util.concurrent.atomic.AtomicLong

import scala.concurrent.Promise
import scala.util.control.NonFatal
import scala.util.{Failure, Success, Try}

import akka.actor.CoordinatedShutdown
import akka.actor.typed.scaladsl.{ActorContext, Behaviors}
import akka.actor.typed.{ActorRef, Behavior, PostStop}

import apps.zeromq.{EndpointProtocol, EndpointRequest, Registering, RequestDesk}
import naogateway.RateLimitedLog
import robotmiddleware.{RobotInterface, RobotMiddleware}

/** The RobotInterface for programs on the same machine at the lowest latency: each request one UDP datagram, the same
  * serialized `Message` with an `rpcRequest` the ZeroMQ endpoint takes, each reply one datagram to the sender's address
  * and port, carrying the request's `callId` (docs/zeromq.md, "The datagram door"). No I/O thread between the socket
  * and the door: the reader thread reads, parses and hands each request on (`RequestDesk`, shared with the ZeroMQ
  * endpoint), and a reply leaves from the thread that has the answer. Calls only: streams and subscriptions stay with
  * the ZeroMQ endpoint.
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
  private final case class ReaderEnded(failure: Option[Throwable]) extends Command

  /** The door for `middleware`'s robots: it registers as app `settings.appName` and ends that session when it stops. */
  def apply(middleware: ActorRef[RobotMiddleware.Command], settings: DatagramDoorSettings): Behavior[Command] =
    Registering[Command](middleware, settings.appName, settings.priority, "datagram door")(Registered,
      { case Registered(r) => r })(
      serving(_, settings, ownsInterface = true))

  /** Spawns the door as a child of `context` when `apps.datagram-door.enabled` is on (it is off in competition). */
  def spawnIfEnabled(
      context: ActorContext[_], middleware: ActorRef[RobotMiddleware.Command]): Option[ActorRef[Command]] = {
    val settings = DatagramDoorSettings(context.system)
    if (settings.enabled) Some(context.spawn(apply(middleware, settings), "datagram-door")) else None
  }

  /** The door in front of `robots`, which the caller owns (and closes). */
  def withInterface(robots: RobotInterface, settings: DatagramDoorSettings): Behavior[Command] =
    serving(robots, settings, ownsInterface = false)

  private def serving(
      robots: RobotInterface, settings: DatagramDoorSettings, ownsInterface: Boolean): Behavior[Command] =
    Behaviors.setup { context =>
      Try(open(settings)) match {
        case Failure(e) =>
          context.log.error("datagram door cannot bind {}:{}: {}", settings.bindAddress, settings.port, e.toString)
          if (ownsInterface) robots.close()
          Behaviors.stopped
        case Success((channel, selector)) =>
          val door = new Door(robots, settings, channel, selector, context)
          context.pipeToSelf(door.ended)(r => ReaderEnded(r.failed.toOption))
          val unbind = CoordinatedShutdown(context.system)
            .addCancellableTask(CoordinatedShutdown.PhaseServiceUnbind, s"$ReaderName-close") { () =>
              door.close()
              scala.concurrent.Future.successful(akka.Done)
            }
          door.start()
          val address = channel.getLocalAddress.asInstanceOf[InetSocketAddress]
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
            case ReaderEnded(failure) =>
              failure match {
                case Some(e) => context.log.error("datagram door: the reader failed; the door stops", e)
                case None    => context.log.info("datagram door: the socket closed; the door stops")
              }
              Behaviors.stopped
            case Registered(_) => Behaviors.unhandled
          }.receiveSignal { case (_, PostStop) =>
            stop()
            Behaviors.same
          }
      }
    }

  private def open(settings: DatagramDoorSettings): (DatagramChannel, Selector) = {
    val channel = DatagramChannel.open()
    try {
      channel.bind(new InetSocketAddress(settings.bindAddress, settings.port))
      channel.configureBlocking(false)
      val selector = Selector.open()
      channel.register(selector, SelectionKey.OP_READ)
      channel -> selector
    } catch {
      case NonFatal(e) =>
        channel.close()
        throw e
    }
  }

  /** The socket, its reader thread, the counters and the desk. The desk's state is guarded by the desk's lock, which
    * the reader takes for each request and an answer's thread for its reply; nothing waits while holding it (the socket
    * does not block).
    */
  private final class Door(
      robots: RobotInterface,
      settings: DatagramDoorSettings,
      channel: DatagramChannel,
      selector: Selector,
      context: ActorContext[Command]
  ) {
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
      context.system.scheduler
    )
    private val reader = new Thread(() => read(), s"${context.system.name}-$ReaderName")
    reader.setDaemon(true)

    /** Completes when the reader has ended: a failure when it failed, success when the socket closed. */
    def ended: scala.concurrent.Future[Unit] = finished.future

    def start(): Unit = reader.start()

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
        Try(channel.close())
        Try(selector.wakeup())
      }
      ()
    }

    private def read(): Unit = {
      // One more byte than the largest request: a datagram that fills it was longer (the rest of it was cut off).
      val buffer = ByteBuffer.allocate(settings.maxDatagramBytes + 1)
      try {
        while (open) {
          selector.select()
          selector.selectedKeys().clear()
          var more = open
          while (more) {
            buffer.clear()
            channel.receive(buffer) match {
              case null => more = false
              case from: InetSocketAddress =>
                buffer.flip()
                received(buffer, from)
              case _ => ()
            }
          }
        }
        finished.trySuccess(())
      } catch {
        case _: ClosedChannelException | _: ClosedSelectorException => finished.trySuccess(())
        case _: IOException if !open                                => finished.trySuccess(())
        case NonFatal(e)                                            => finished.tryFailure(e)
      } finally Try(selector.close())
      ()
    }

    private def received(buffer: ByteBuffer, from: InetSocketAddress): Unit =
      if (buffer.remaining > settings.maxDatagramBytes) dropped(Drop.Oversize, from)
      else {
        val bytes = new Array[Byte](buffer.remaining)
        buffer.get(bytes)
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

    private def send(to: InetSocketAddress, reply: Array[Byte]): Unit = {
      val sent =
        try channel.send(ByteBuffer.wrap(reply), to) > 0
        catch { case NonFatal(_) => false }
      if (!sent) dropped(Drop.ReplyNotSent, to)
    }

    private def dropped(kind: Drop, from: InetSocketAddress): Unit = {
      val n = drops(kind).incrementAndGet()
      if (RateLimitedLog.due(n))
        log.warn("datagram door: {} datagram dropped from {} ({} of this kind so far)", kind.name,
          from, n)
    }
  }
}
