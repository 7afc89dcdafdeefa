package apps.control

import java.net.InetSocketAddress
import java.nio.charset.StandardCharsets
import java.util.concurrent.TimeoutException
import java.util.concurrent.atomic.AtomicInteger

import scala.concurrent.duration._
import scala.concurrent.{ExecutionContext, Future}
import scala.util.control.NonFatal
import scala.util.{Failure, Success}

import akka.actor.typed.scaladsl.{ActorContext, Behaviors}
import akka.actor.typed.{ActorRef, ActorSystem, Behavior, PostStop}
import akka.stream.scaladsl.{Flow, Framing, Sink, Source, Tcp}
import akka.stream.Materializer
import akka.util.ByteString
import akka.{Done, NotUsed}

import apps.control.ControlProtocol.{Answer, Request}
import naogateway.{LinkStats, RobotSnapshot}
import robotmiddleware.{Operation, RobotClient, RobotFailure, RobotInterface, RobotMiddleware}

/**
 * The control port: a loopback TCP server on the gateway node that answers robotctl's requests through the
 * `RobotInterface` (wire format in [[ControlProtocol]]). One request per connection; the answer streams line by
 * line, so a status of a thousand robots is a thousand short lines, never one large message.
 */
object ControlServer {

  /** What the control server accepts. */
  sealed trait Command

  /** Answers with the bound address (the real port when 0 was configured), once bound. */
  final case class GetAddress(replyTo: ActorRef[InetSocketAddress]) extends Command

  private final case class Connected(robots: RobotInterface) extends Command
  private final case class ConnectFailed(reason: Throwable) extends Command
  private final case class Bound(binding: Tcp.ServerBinding) extends Command
  private final case class BindFailed(reason: Throwable) extends Command

  /** The server for `middleware`'s robots: it registers as app `settings.appName` and ends that session when it stops. */
  def apply(middleware: ActorRef[RobotMiddleware.Command], settings: ControlSettings): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withStash(16) { stash =>
        context.pipeToSelf(RobotClient.connect(context.system, middleware, settings.appName, settings.priority)) {
          case Success(robots) => Connected(robots)
          case Failure(e)      => ConnectFailed(e)
        }
        Behaviors.receiveMessage {
          case Connected(robots) => stash.unstashAll(serving(robots, settings, ownsInterface = true))
          case ConnectFailed(e) =>
            context.log.error("Control port: cannot register with the middleware; robotctl will find no gateway", e)
            Behaviors.stopped
          case other =>
            if (stash.isFull) context.log.warn("Control port: message dropped while registering") else stash.stash(other)
            Behaviors.same
        }
      }
    }

  /** Spawns the server as a child of `context` when `apps.control.enabled` is on (it is, by default). */
  def spawnIfEnabled(context: ActorContext[_], middleware: ActorRef[RobotMiddleware.Command]): Option[ActorRef[Command]] = {
    val settings = ControlSettings(context.system)
    if (settings.enabled) Some(context.spawn(apply(middleware, settings), "control")) else None
  }

  /** The server in front of `robots`, which the caller owns (and closes). */
  def withInterface(robots: RobotInterface, settings: ControlSettings): Behavior[Command] =
    serving(robots, settings, ownsInterface = false)

  private def serving(robots: RobotInterface, settings: ControlSettings, ownsInterface: Boolean): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withStash(16) { stash =>
        implicit val system: ActorSystem[_] = context.system
        // Touched by the connections' stream callbacks, never by the actor's state.
        val open = new AtomicInteger
        val handler = answering(robots, settings)
        val busy = Flow.fromSinkAndSourceCoupled(Sink.ignore,
          Source.single(line(Answer.Error(s"busy: ${settings.maxConnections} robotctl commands are being served; try again"))))
        val binding = Tcp(system)
          .bind(settings.host, settings.port)
          .to(Sink.foreach { connection =>
            if (open.incrementAndGet() > settings.maxConnections) {
              open.decrementAndGet()
              connection.handleWith(busy)
            } else
              connection.handleWith(handler.watchTermination()((_, done) => done))
                .onComplete(_ => open.decrementAndGet())(ExecutionContext.parasitic)
          })
          .run()
        context.pipeToSelf(binding) {
          case Success(b) => Bound(b)
          case Failure(e) => BindFailed(e)
        }

        def cleanUp(): Unit = {
          binding.foreach(_.unbind())(ExecutionContext.parasitic)
          if (ownsInterface) robots.close()
        }

        def waitingForBind(): Behavior[Command] = Behaviors.receiveMessage[Command] {
          case Bound(b) =>
            val address = b.localAddress
            if (!address.getAddress.isLoopbackAddress)
              context.log.warn("Control port {} is not on loopback: anyone who reaches it can move the robots", address)
            context.log.info("Control port serving robotctl on {}", s"${address.getAddress.getHostAddress}:${address.getPort}")
            stash.unstashAll(running(address))
          case BindFailed(e) =>
            context.log.error("Control port cannot bind {}:{}, robotctl will not reach this gateway: {}", settings.host, settings.port, e.getMessage)
            Behaviors.stopped
          case other =>
            if (stash.isFull) context.log.warn("Control port: message dropped while binding") else stash.stash(other)
            Behaviors.same
        }.receiveSignal { case (_, PostStop) => cleanUp(); Behaviors.same }

        def running(address: InetSocketAddress): Behavior[Command] = Behaviors.receiveMessage[Command] {
          case GetAddress(replyTo) =>
            replyTo ! address
            Behaviors.same
          case Bound(_) | BindFailed(_) | Connected(_) | ConnectFailed(_) => Behaviors.unhandled
        }.receiveSignal { case (_, PostStop) => cleanUp(); Behaviors.same }

        waitingForBind()
      }
    }

  private def line(answer: Answer): ByteString = ByteString(ControlProtocol.render(answer) + "\n", StandardCharsets.UTF_8)

  /**
   * One connection: reads one request line (bounded; it must come within `request-timeout`), then streams its
   * answer and completes, which closes the connection. Bad input gets an error line, never more.
   */
  def answering(robots: RobotInterface, settings: ControlSettings)(implicit system: ActorSystem[_]): Flow[ByteString, ByteString, NotUsed] =
    Flow[ByteString]
      // +1: a terminal client's \r before the \n.
      .via(Framing.delimiter(ByteString("\n"), ControlProtocol.MaxRequestBytes + 1, allowTruncation = true))
      .take(1)
      .initialTimeout(settings.requestTimeout)
      .map[Either[String, Request]](bytes => ControlProtocol.readRequest(bytes.decodeString(StandardCharsets.UTF_8)))
      .orElse(Source.single(Left("no request line")))
      .recover {
        case _: Framing.FramingException => Left(s"request line longer than ${ControlProtocol.MaxRequestBytes} bytes")
        case _: TimeoutException => Left(s"no request line within ${settings.requestTimeout.toSeconds} s")
      }
      .flatMapConcat {
        case Left(error)    => Source.single(Answer.Error(error))
        case Right(request) => answer(robots, settings, request)
      }
      .map(line(_))

  /** The answer to `request`: output lines, then exactly one `Ok` or `Error`, within the request's time limit. */
  def answer(robots: RobotInterface, settings: ControlSettings, request: Request)(implicit system: ActorSystem[_]): Source[Answer, NotUsed] = {
    val limit = request match {
      case Request.Watch(_, seconds) => settings.answerTimeout + seconds.seconds
      case _                         => settings.answerTimeout
    }
    val answers = try body(robots, settings, request) catch { case NonFatal(e) => Source.failed(e) }
    answers
      .completionTimeout(limit)
      .recover {
        case _: TimeoutException => Answer.Error(s"no answer within ${limit.toSeconds} s")
        case NonFatal(e)         => Answer.Error(errorText(e))
      }
      // Whatever a robot put in its texts, no answer line outgrows the protocol's limit.
      .mapConcat {
        case Answer.Line(text)  => ControlProtocol.lines(text)
        case Answer.Ok(text)    => List(Answer.Ok(text.take(MaxFinalChars)))
        case Answer.Error(text) => List(Answer.Error(text.take(MaxFinalChars)))
      }
  }

  // The final line's text, in characters: at most 6 bytes each once escaped, well inside MaxAnswerBytes.
  private val MaxFinalChars = 1000

  private def body(robots: RobotInterface, settings: ControlSettings, request: Request)(implicit system: ActorSystem[_]): Source[Answer, NotUsed] = {
    implicit val ec: ExecutionContext = system.executionContext
    request match {
      case Request.Status =>
        Source.future(robots.robots()).flatMapConcat { all =>
          // Every robot's link figures are asked for at once: they are pushed once per link-stats-interval, so the
          // status takes one interval in all rather than one per robot. Bounded by the robots the gateway knows.
          val stats = all.map(r => linkStats(robots, r.robotId, settings.linkStatsTimeout))
          Source.single(Answer.Line(statusHeader))
            .concat(Source(all.zip(stats)).mapAsync(1) { case (r, s) => s.map(st => Answer.Line(statusLine(r, st))) })
            .concat(Source.single(Answer.Ok("")))
        }
      case Request.Call(id, module, method, params) =>
        val needs = Operation.RawCall(module, method, params).group
        val done = needs.fold(Future.successful(Done: Done))(g => robots.acquire(id, g)).flatMap { _ =>
          robots.call(id, module, method, params: _*).andThen { case _ => needs.foreach(g => robots.release(id, g)) }
        }
        Source.future(done).mapConcat { v =>
          List(Answer.Line(s"robot $id: $module.$method -> ${v.fold("(no value)")(_.toString)}"), Answer.Ok(""))
        }
      case Request.Watch(id, seconds) =>
        if (seconds.seconds > settings.maxWatch) Source.single(Answer.Error(s"a watch lasts at most ${settings.maxWatch.toSeconds} s"))
        else
          Source.future(robots.robots()).flatMapConcat { all =>
            if (!all.exists(_.robotId == id)) Source.failed(RobotFailure.UnknownRobot(id))
            else
              Source.single(Answer.Line(statusHeader))
                .concat(robots.status(id).takeWithin(seconds.seconds).map(s => Answer.Line(statusLine(s, None))))
                .concat(Source.single(Answer.Ok(s"watched robot $id for $seconds s")))
          }
    }
  }

  /** The robot's next link figures, or None when none come within `timeout`. */
  private def linkStats(robots: RobotInterface, robotId: Int, timeout: FiniteDuration)(implicit mat: Materializer): Future[Option[LinkStats]] =
    robots.linkStats(robotId).takeWithin(timeout).runWith(Sink.headOption).recover { case NonFatal(_) => None }(ExecutionContext.parasitic)

  /** The text of a failure, as robotctl prints it. */
  def errorText(e: Throwable): String = e match {
    case f: RobotFailure => f.getMessage
    case other           => Option(other.getMessage).filter(_.nonEmpty).getOrElse(other.getClass.getSimpleName)
  }

  /** The column heads of [[statusLine]]. */
  val statusHeader: String =
    f"${"id"}%-4s ${"address"}%-22s ${"state"}%-8s ${"link"}%-9s ${"battery"}%-8s ${"posture"}%-8s ${"role"}%-9s ${"rtt"}%-9s loss"

  /** One line per robot: id, address, online, link quality, battery, posture, role, round-trip time, loss. */
  def statusLine(r: RobotSnapshot, stats: Option[LinkStats]): String = {
    val address = s"${r.address.getAddress.getHostAddress}:${r.address.getPort}"
    val rtt = stats.flatMap(_.rttMillis).fold("-")(v => f"$v%.1f ms")
    val loss = stats.fold("-")(s => f"${s.lossEstimate * 100}%.0f %%")
    f"${r.robotId}%-4d $address%-22s ${if (r.online) "online" else "offline"}%-8s ${r.quality.name}%-9s " +
      f"${r.batteryVoltage.fold("-")(v => f"$v%.2f V")}%-8s ${r.posture.getOrElse("-")}%-8s ${r.role.getOrElse("-")}%-9s $rtt%-9s $loss"
  }
}
