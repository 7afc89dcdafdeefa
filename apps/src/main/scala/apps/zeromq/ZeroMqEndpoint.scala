package apps.zeromq

import java.nio.charset.StandardCharsets

import scala.concurrent.duration._
import scala.concurrent.ExecutionContext
import scala.jdk.CollectionConverters._
import scala.util.control.NonFatal
import scala.util.Try

import akka.actor.typed.scaladsl.{ActorContext, Behaviors, StashBuffer, TimerScheduler}
import akka.actor.typed.{ActorRef, ActorSystem, Behavior, DispatcherSelector, PostStop, Signal}
import akka.actor.{Cancellable, CoordinatedShutdown}
import akka.stream.scaladsl.Keep
import akka.stream.typed.scaladsl.ActorSink
import akka.stream.{KillSwitches, SharedKillSwitch, UniqueKillSwitch}
import org.zeromq.{SocketType, ZMQ, ZMsg}

import naogateway.transport.ZeroMqLoop
import naogateway.wire.gamecontroller.GameControlData
import naogateway.api.{RobotSnapshot, VisionFrame}
import robotmiddleware.{RobotInterface, RobotMiddleware}

/** The RobotInterface for programs in any language: requests on a ZeroMQ ROUTER socket, robot data on an XPUB socket
  * (docs/zeromq.md). The sockets live on a `ZeroMqLoop` on the endpoint's own dispatcher. The loop's thread owns the
  * requests too (`Desk`): it reads each one, hands it to the `RobotInterface` and writes its reply, so a request passes
  * no mailbox on its way in, and an answer that is there at once leaves without waking the loop again. This actor owns
  * the rest (binding, the published streams, the subscriptions, the shutdown); nothing blocks anywhere.
  */
object ZeroMqEndpoint {

  /** What the endpoint accepts. */
  sealed trait Command

  /** Answers with the bound endpoints (the real ports when `*` was configured), once bound. */
  final case class GetAddresses(replyTo: ActorRef[Addresses]) extends Command

  /** Where the endpoint listens: requests (ROUTER) and publications (XPUB). */
  final case class Addresses(requests: String, publish: String)

  private final case class Registered(result: Try[RobotInterface]) extends Command
  private final case class Bound(addresses: Addresses) extends Command
  private final case class BindFailed(reason: String) extends Command
  private final case class SubscriptionChanged(prefix: String, subscribed: Boolean) extends Command
  private final case class StatusSeen(snapshot: RobotSnapshot) extends Command
  private final case class GameSeen(data: GameControlData) extends Command
  private final case class VisionSeen(frame: VisionFrame) extends Command
  private final case class StreamEnded(stream: String, failure: Option[Throwable]) extends Command
  private case object LoopEnded extends Command
  private case object BindTimedOut extends Command
  private case object BindKey

  /** The loop thread's name suffix (tests look for it to see that the thread has ended). */
  val LoopName: String = "zeromq-endpoint"

  // Replies still queued when the endpoint stops get this long to reach their clients.
  private val FlushOnCloseMillis = 200
  private val BindTimeout = 10.seconds
  // A request is a few hundred bytes; a client sending more is broken or hostile and is disconnected.
  private val MaxRequestBytes = 1024L * 1024L

  /** The endpoint for `middleware`'s robots: it registers as app `settings.appName` and ends that session when it
    * stops.
    */
  def apply(middleware: ActorRef[RobotMiddleware.Command], settings: ZeroMqSettings): Behavior[Command] =
    Registering[Command](middleware, settings.appName, settings.priority, "ZeroMQ endpoint")(Registered,
      { case Registered(r) => r })(
      serving(_, settings, ownsInterface = true))

  /** Spawns the endpoint as a child of `context` when `apps.zeromq.enabled` opens it ([[apps.Doors.open]]: `auto` keeps
    * it shut while `realRobots`) and its endpoints are loopback; a refused endpoint is logged, not started.
    */
  def spawnIfEnabled(context: ActorContext[_], middleware: ActorRef[RobotMiddleware.Command],
      realRobots: Boolean): Option[ActorRef[Command]] = {
    val settings = ZeroMqSettings(context.system)
    if (!apps.Doors.open(settings.enabled, realRobots)) None
    else settings.refusal match {
      case Some(reason) =>
        context.log.error("ZeroMQ endpoint not started: {}", reason)
        None
      case None => Some(context.spawn(apply(middleware, settings), "zeromq-endpoint"))
    }
  }

  /** The endpoint in front of `robots`, which the caller owns (and closes). */
  def withInterface(robots: RobotInterface, settings: ZeroMqSettings): Behavior[Command] =
    serving(robots, settings, ownsInterface = false)

  private def serving(robots: RobotInterface, settings: ZeroMqSettings, ownsInterface: Boolean): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        Behaviors.withStash(64) { stash =>
          new Endpoint(robots, settings, ownsInterface, context, timers, stash).start()
        }
      }
    }

  /** The sockets; created, used and closed only on the loop's thread. */
  private final class Io {
    var router: ZMQ.Socket = null
    var publisher: ZMQ.Socket = null

    def send(socket: ZMQ.Socket, frames: Vector[Array[Byte]]): Unit =
      if (socket != null && frames.nonEmpty) {
        // Neither ROUTER nor XPUB blocks: a message for a gone or too slow peer is dropped.
        frames.init.foreach(f => socket.send(f, ZMQ.SNDMORE | ZMQ.DONTWAIT))
        socket.send(frames.last, ZMQ.DONTWAIT)
      }
  }

  private final class Endpoint(
      robots: RobotInterface,
      settings: ZeroMqSettings,
      ownsInterface: Boolean,
      context: ActorContext[Command],
      timers: TimerScheduler[Command],
      stash: StashBuffer[Command]
  ) {
    private implicit val system: ActorSystem[_] = context.system
    // Only for composing the interface's futures; none of their callbacks touches the actor's state.
    private implicit val ec: ExecutionContext = context.executionContext
    private val loop = new ZeroMqLoop(LoopName, settings.pollTimeout)
    private val io = new Io
    private val streams: SharedKillSwitch = KillSwitches.shared("zeromq-endpoint")
    private var visionStreams = Map.empty[Int, UniqueKillSwitch]
    private val desk = new Desk
    private var prefixes = Set.empty[String]
    private var knownRobots = Set.empty[Int]
    private var shutdownTask: Option[Cancellable] = None

    def start(): Behavior[Command] = {
      loop.start(context.system.dispatchers.lookup(DispatcherSelector.fromConfig(settings.dispatcher)))
      context.pipeToSelf(loop.terminated)(_ => LoopEnded)
      // The sockets close early in a coordinated shutdown, before the actors are stopped.
      shutdownTask =
        Some(CoordinatedShutdown(context.system).addCancellableTask(CoordinatedShutdown.PhaseServiceUnbind, LoopName) {
          () => loop.stop()
        })
      bind()
      // The loop needs a thread of its own: with every thread of the dispatcher taken by other loops it never starts.
      timers.startSingleTimer(BindKey, BindTimedOut, BindTimeout)
      binding
    }

    private def bind(): Unit = {
      val self = context.self
      loop.submit { sockets =>
        var opened = List.empty[ZMQ.Socket]
        try {
          // Refused off loopback whoever spawns it: the endpoint has no token.
          settings.refusal.foreach(r => throw new IllegalArgumentException(r))
          val router = sockets.socket(SocketType.ROUTER)
          opened ::= router
          router.setLinger(FlushOnCloseMillis)
          router.setMaxMsgSize(MaxRequestBytes)
          router.bind(settings.bind)
          val publisher = sockets.socket(SocketType.XPUB)
          opened ::= publisher
          publisher.bind(settings.publish)
          io.router = router
          io.publisher = publisher
          sockets.onReadable(router) { s =>
            val message = ZMsg.recvMsg(s, ZMQ.DONTWAIT)
            if (message == null) false
            else {
              desk.received(message.asScala.map(_.getData).toVector)
              message.destroy()
              true
            }
          }
          sockets.onReadable(publisher) { s =>
            val frame = s.recv(ZMQ.DONTWAIT)
            if (frame == null) false
            else {
              // XPUB hands up each new subscription (1 + prefix) and each last unsubscription (0 + prefix).
              if (frame.nonEmpty && (frame(0) == 0 || frame(0) == 1))
                self ! SubscriptionChanged(new String(frame, 1, frame.length - 1, StandardCharsets.UTF_8),
                  frame(0) == 1)
              true
            }
          }
          self ! Bound(Addresses(router.getLastEndpoint, publisher.getLastEndpoint))
        } catch {
          case NonFatal(e) =>
            opened.foreach(sockets.close)
            self ! BindFailed(s"$e")
        }
      }
      ()
    }

    private val cleanUp: PartialFunction[(ActorContext[Command], Signal), Behavior[Command]] = { case (_, PostStop) =>
      stopEverything()
      Behaviors.same
    }

    private def binding: Behavior[Command] = Behaviors.receiveMessage[Command] {
      case Bound(addresses) =>
        timers.cancel(BindKey)
        context.log.info("ZeroMQ endpoint serving requests on {} and publishing on {}", addresses.requests,
          addresses.publish)
        startStreams()
        stash.unstashAll(running(addresses))
      case BindFailed(reason) =>
        context.log.error("ZeroMQ endpoint cannot bind {} / {}: {}", settings.bind, settings.publish, reason)
        Behaviors.stopped
      case LoopEnded =>
        context.log.error("ZeroMQ endpoint: the socket loop ended before binding")
        Behaviors.stopped
      case BindTimedOut =>
        context.log.error(
          "ZeroMQ endpoint: the socket loop did not start within {}; does dispatcher {} have a free thread?",
          BindTimeout, settings.dispatcher)
        Behaviors.stopped
      case other =>
        if (stash.isFull) context.log.warn("ZeroMQ endpoint: message dropped while binding") else stash.stash(other)
        Behaviors.same
    }.receiveSignal(cleanUp)

    private def startStreams(): Unit = {
      def sink(name: String) =
        ActorSink.actorRef[Command](context.self, StreamEnded(name, None), (e: Throwable) => StreamEnded(name, Some(e)))
      robots.allStatus.via(streams.flow).map[Command](StatusSeen.apply).runWith(sink("status"))
      robots.gameState.via(streams.flow).map[Command](GameSeen.apply).runWith(sink("game"))
      ()
    }

    /** Vision costs the robots' bandwidth, so a robot's camera stream runs only while someone subscribes to it. */
    private def reconcileVision(): Unit =
      knownRobots.foreach { robotId =>
        (EndpointProtocol.wantsVision(prefixes, robotId), visionStreams.get(robotId)) match {
          case (true, None) =>
            context.log.info("ZeroMQ endpoint: vision of robot [{}] subscribed", robotId)
            val killSwitch = robots
              .vision(robotId)
              .viaMat(KillSwitches.single)(Keep.right)
              .map[Command](VisionSeen.apply)
              .to(ActorSink.actorRef[Command](context.self, StreamEnded(s"vision-$robotId", None),
                  (e: Throwable) => StreamEnded(s"vision-$robotId", Some(e))))
              .run()
            visionStreams = visionStreams.updated(robotId, killSwitch)
          case (false, Some(killSwitch)) =>
            context.log.info("ZeroMQ endpoint: vision of robot [{}] no longer subscribed", robotId)
            killSwitch.shutdown()
            visionStreams -= robotId
          case _ => ()
        }
      }

    private def send(frames: Vector[Array[Byte]], toRouter: Boolean): Unit = {
      loop.submit(_ => io.send(if (toRouter) io.router else io.publisher, frames))
      ()
    }

    /** The requests, owned by the loop's thread: every method runs there (inside the loop's handlers and operations),
      * so none of this state is shared. Answers that complete elsewhere come back as loop operations.
      */
    private final class Desk {
      private val requests = new RequestDesk[Vector[Array[Byte]]](
        robots,
        "ZeroMQ endpoint",
        settings.requestTimeout,
        operation => { loop.submit(_ => operation()); () },
        (envelope, body) => io.send(io.router, envelope :+ body),
        Endpoint.this.ec,
        system.scheduler,
        robotmiddleware.MiddlewareSettings(system).servoLimits
      )

      /** One request read from the router. */
      def received(frames: Vector[Array[Byte]]): Unit = {
        val (envelope, body) = split(frames)
        body match {
          case Left(error) => requests.reply(envelope, -1, None, Left(error))
          case Right(bytes) =>
            EndpointProtocol.parse(bytes) match {
              case Left(unreadable) =>
                requests.reply(envelope, unreadable.robotId, unreadable.callId, Left(unreadable.error))
              case Right(request) =>
                if (requests.inFlight >= settings.maxInFlight)
                  requests.reply(envelope, request.robotId, request.call.callId,
                    Left(s"overloaded: ${requests.inFlight} requests are in progress at the endpoint"))
                else requests.accept(envelope, request)
            }
        }
      }

      /** Requests still being worked on get an answer while the socket is still there to carry it. */
      def shutDown(): Unit = requests.shutDown()

      /** The envelope (routing id, and the empty delimiter of REQ clients) and the one body frame. */
      private def split(frames: Vector[Array[Byte]]): (Vector[Array[Byte]], Either[String, Array[Byte]]) = {
        val delimiter = frames.indexWhere(_.isEmpty)
        val (envelope, rest) = if (delimiter >= 0) frames.splitAt(delimiter + 1) else frames.splitAt(1)
        rest match {
          case Vector(body) => envelope -> Right(body)
          case Vector()     => envelope -> Left(s"${EndpointProtocol.Malformed}no body frame")
          case more => envelope -> Left(s"${EndpointProtocol.Malformed}expected one body frame, got ${more.size}")
        }
      }
    }

    private def running(addresses: Addresses): Behavior[Command] = Behaviors.receiveMessage[Command] {
      case StatusSeen(snapshot) =>
        /* Nobody subscribed: nothing is encoded and the socket loop sleeps on (every robot's keep-alives would wake
         * it). */
        if (EndpointProtocol.subscribed(prefixes, EndpointProtocol.statusTopic(snapshot.robotId)))
          send(EndpointProtocol.statusFrames(snapshot), toRouter = false)
        if (!knownRobots(snapshot.robotId)) {
          knownRobots += snapshot.robotId
          reconcileVision()
        }
        Behaviors.same
      case GameSeen(data) =>
        if (EndpointProtocol.subscribed(prefixes, EndpointProtocol.GameTopic))
          EndpointProtocol.gameFrames(data).foreach(send(_, toRouter = false))
        Behaviors.same
      case VisionSeen(frame) =>
        EndpointProtocol.visionFrames(frame).foreach(send(_, toRouter = false))
        Behaviors.same
      case SubscriptionChanged(prefix, subscribed) =>
        context.log.debug("ZeroMQ endpoint: subscription [{}] {}", prefix, if (subscribed) "on" else "off")
        prefixes = if (subscribed) prefixes + prefix else prefixes - prefix
        reconcileVision()
        Behaviors.same
      case StreamEnded(stream, failure) =>
        failure match {
          case Some(e) => context.log.warn("ZeroMQ endpoint: stream {} failed", stream, e)
          case None    => context.log.debug("ZeroMQ endpoint: stream {} ended", stream)
        }
        Behaviors.same
      case GetAddresses(replyTo) =>
        replyTo ! addresses
        Behaviors.same
      case LoopEnded =>
        context.log.info("ZeroMQ endpoint: socket loop ended; the endpoint stops")
        Behaviors.stopped
      case Bound(_) | BindFailed(_) | Registered(_) | BindTimedOut => Behaviors.unhandled
    }.receiveSignal(cleanUp)

    private def stopEverything(): Unit = {
      // Before the loop stops: its operations submitted before `stop` still run, with the socket still there.
      loop.submit(_ => desk.shutDown())
      streams.shutdown()
      visionStreams.values.foreach(_.shutdown())
      loop.stop()
      shutdownTask.foreach(_.cancel())
      if (ownsInterface) robots.close()
      context.log.info("ZeroMQ endpoint stopped")
    }
  }
}
