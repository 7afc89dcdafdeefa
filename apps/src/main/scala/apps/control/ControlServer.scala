package apps.control

import naogateway.api.RobotFailure

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
import akka.stream.scaladsl.{Flow, Sink, Source, Tcp}
import akka.stream.Materializer
import akka.util.ByteString
import akka.{Done, NotUsed}

import apps.control.ControlProtocol.{Answer, Request}
import naogateway.api.{GameSource, GatewayView, LinkStats, RobotSnapshot}
import robotmiddleware.{Operation, RobotClient, RobotInterface, RobotMiddleware}

/** The control port: a loopback TCP server on the gateway node that answers robotctl's requests through the
  * `RobotInterface` (wire format in [[ControlProtocol]]). One request per connection; the answer streams line by line,
  * so a status of a thousand robots is a thousand short lines, never one large message.
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

  /** What the control port reads beside the robots, handed in by the launcher: the gateway's read-only view (for the
    * game lines of `status`), the doctor's checks (for `doctor`), which only the launcher can make, and the demo's
    * battery swap (`battery <id> swap`: the text to print, or a failure saying why not, e.g. for a real robot).
    */
  final case class GatewaySide(view: GatewayView, doctor: () => Future[Vector[Finding]],
      batterySwap: Int => Future[String] = GatewaySide.noSimulatedRobots)

  /** The launcher's side of the control port. */
  object GatewaySide {

    /** The swap of a gateway with no simulated robots: every robot is a real one. */
    val noSimulatedRobots: Int => Future[String] = id => Future.failed(new IllegalArgumentException(notSimulated(id)))

    /** Why robot `robotId`'s battery cannot be swapped from here. */
    def notSimulated(robotId: Int): String =
      s"robot $robotId is not a simulated robot: robotctl battery swaps only the demo's simulated robots' batteries; " +
        "swap a real robot's battery by hand"
  }

  /** The server for `middleware`'s robots: it registers as app `settings.appName` and ends that session when it stops.
    */
  def apply(middleware: ActorRef[RobotMiddleware.Command], settings: ControlSettings,
      gateway: Option[GatewaySide] = None): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withStash(16) { stash =>
        context.pipeToSelf(RobotClient.connect(context.system, middleware, settings.appName, settings.priority)) {
          case Success(robots) => Connected(robots)
          case Failure(e)      => ConnectFailed(e)
        }
        Behaviors.receiveMessage {
          case Connected(robots) => stash.unstashAll(serving(robots, settings, ownsInterface = true, gateway))
          case ConnectFailed(e) =>
            context.log.error("Control port: cannot register with the middleware; robotctl will find no gateway", e)
            Behaviors.stopped
          case other =>
            if (stash.isFull) context.log.warn("Control port: message dropped while registering")
            else stash.stash(other)
            Behaviors.same
        }
      }
    }

  /** Spawns the server as a child of `context` when `apps.control.enabled` is on (it is, by default). */
  def spawnIfEnabled(context: ActorContext[_], middleware: ActorRef[RobotMiddleware.Command],
      gateway: Option[GatewaySide] = None): Option[ActorRef[Command]] = {
    val settings = ControlSettings(context.system)
    if (settings.enabled) Some(context.spawn(apply(middleware, settings, gateway), "control")) else None
  }

  /** The server in front of `robots`, which the caller owns (and closes). */
  def withInterface(robots: RobotInterface, settings: ControlSettings,
      gateway: Option[GatewaySide] = None): Behavior[Command] =
    serving(robots, settings, ownsInterface = false, gateway)

  private def serving(robots: RobotInterface, settings: ControlSettings, ownsInterface: Boolean,
      gateway: Option[GatewaySide]): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withStash(16) { stash =>
        implicit val system: ActorSystem[_] = context.system
        // Touched by the connections' stream callbacks, never by the actor's state.
        val open = new AtomicInteger
        val handler = answering(settings)(answer(robots, settings, _, gateway))
        // A client told it is busy has its request line read first: closing a socket with unread input resets the
        // connection, and the client would see "connection reset" instead of the reason.
        val busyAnswer = Answer.Error(s"busy: ${settings.maxConnections} robotctl commands are being served; try again")
        val busy = answering(settings)(_ => Source.single(busyAnswer))
        val turnedAway = new AtomicInteger
        val binding = Tcp(system)
          // Half-close on: once the request line is read, the read side is cancelled, and with half-close off that
          // would close the connection before the answer is written. Completing the answer closes it.
          .bind(settings.host, settings.port, halfClose = true)
          .to(Sink.foreach { connection =>
            if (open.incrementAndGet() <= settings.maxConnections)
              connection.handleWith(handler.watchTermination()((_, done) => done))
                .onComplete(_ => open.decrementAndGet())(ExecutionContext.parasitic)
            else {
              open.decrementAndGet()
              // As many again are told why; beyond that a flood of connections is closed at once.
              if (turnedAway.incrementAndGet() <= settings.maxConnections)
                connection.handleWith(busy.watchTermination()((_, done) => done))
                  .onComplete(_ => turnedAway.decrementAndGet())(ExecutionContext.parasitic)
              else {
                turnedAway.decrementAndGet()
                connection.handleWith(Flow.fromSinkAndSource(Sink.cancelled[ByteString], Source.empty[ByteString]))
              }
            }
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
            context.log.info("Control port serving robotctl on {}",
              s"${address.getAddress.getHostAddress}:${address.getPort}")
            stash.unstashAll(running(address))
          case BindFailed(e) =>
            context.log.error("Control port cannot bind {}:{}, robotctl will not reach this gateway: {}", settings.host,
              settings.port, e.getMessage)
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

  private def line(answer: Answer): ByteString =
    ByteString(ControlProtocol.render(answer) + "\n", StandardCharsets.UTF_8)

  /** One connection: reads one request line (bounded; it must come within `request-timeout`), then streams the answer
    * `respond` gives and completes, which closes the connection. Bad input gets an error line, never more.
    */
  def answering(settings: ControlSettings)(
      respond: Request => Source[Answer, NotUsed]): Flow[ByteString, ByteString, NotUsed] =
    Flow[ByteString]
      .map[Input](Input.Chunk(_))
      .concat(Source.single(Input.End))
      .merge(Source.single(Input.TimedOut).initialDelay(settings.requestTimeout))
      .statefulMapConcat { () =>
        val reader = new LineReader(settings.requestTimeout)
        input => reader.next(input)
      }
      // Nothing on this side fails: a failure would cancel the read side with an error, and the connection would be
      // reset (the client seeing no answer) instead of closed after the answer.
      .take(1)
      .flatMapConcat {
        case Left(error)    => Source.single(Answer.Error(error))
        case Right(request) => respond(request)
      }
      .map(line(_))
      // A client that stops reading would hold its connection for ever (its answer waits for TCP to take it): past
      // the longest any exchange may take, the connection is aborted.
      .completionTimeout(settings.requestTimeout + settings.answerTimeout + settings.maxWatch + 10.seconds)

  /** What the line reader sees of a connection. */
  private sealed trait Input
  private object Input {
    final case class Chunk(bytes: ByteString) extends Input
    case object End extends Input
    case object TimedOut extends Input
  }

  /** Finds the request line in a connection's input: at most [[ControlProtocol.MaxRequestBytes]] are kept; an overlong
    * line is read to its end and dropped, so the client's input is consumed before it is answered.
    */
  private final class LineReader(requestTimeout: FiniteDuration) {
    // +1: a terminal client's \r before the \n.
    private val max = ControlProtocol.MaxRequestBytes + 1
    private var kept = ByteString.empty
    private var overlong = false
    private var answered = false

    def next(input: Input): List[Either[String, Request]] =
      if (answered) Nil
      else
        input match {
          case Input.Chunk(bytes) =>
            val newline = bytes.indexOf('\n'.toByte)
            val part = if (newline < 0) bytes else bytes.take(newline)
            if (!overlong) {
              if (kept.length + part.length > max) { overlong = true; kept = ByteString.empty }
              else kept ++= part
            }
            if (newline < 0) Nil else finish(input)
          case Input.End | Input.TimedOut => finish(input)
        }

    private def finish(ending: Input): List[Either[String, Request]] = {
      answered = true
      val request =
        if (overlong) Left(s"request line longer than ${ControlProtocol.MaxRequestBytes} bytes")
        else
          ending match {
            case Input.TimedOut            => Left(s"no request line within ${requestTimeout.toSeconds} s")
            case Input.End if kept.isEmpty => Left("no request line")
            // The line up to its \n, or a last line without one when the client ended its input.
            case _ => ControlProtocol.readRequest(kept.decodeString(StandardCharsets.UTF_8))
          }
      List(request)
    }
  }

  /** The answer to `request`: output lines, then exactly one `Ok` or `Error`, within the request's time limit. */
  def answer(robots: RobotInterface, settings: ControlSettings, request: Request,
      gateway: Option[GatewaySide] = None)(implicit system: ActorSystem[_]): Source[Answer, NotUsed] = {
    val limit = request match {
      case Request.Watch(_, seconds) => settings.answerTimeout + seconds.seconds
      case _                         => settings.answerTimeout
    }
    val answers =
      try body(robots, settings, request, gateway)
      catch { case NonFatal(e) => Source.failed(e) }
    answers
      .completionTimeout(limit)
      .recover {
        case _: TimeoutException => Answer.Error(s"no answer within ${limit.toSeconds} s")
        case NonFatal(e)         => Answer.Error(ControlText.errorText(e))
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

  private def body(robots: RobotInterface, settings: ControlSettings, request: Request,
      gateway: Option[GatewaySide])(implicit system: ActorSystem[_]): Source[Answer, NotUsed] = {
    implicit val ec: ExecutionContext = system.executionContext
    // Which servos the status lines mark (robotmiddleware.servos); read when a line needs it.
    lazy val servoLimits = robotmiddleware.MiddlewareSettings(system).servoLimits
    request match {
      case Request.Status =>
        Source.future(robots.robots()).flatMapConcat { all =>
          // Every robot's link figures are asked for at once: they are pushed once per link-stats-interval, so the
          // status takes one interval in all rather than one per robot. Bounded by the robots the gateway knows.
          val stats = all.map(r => linkStats(robots, r.robotId, settings.linkStatsTimeout))
          // The lease holders and holds as the middleware has them; none listed when it does not answer in time.
          val holds = within(robots.holds(), settings.linkStatsTimeout).recover { case NonFatal(_) => Vector.empty }
          Source.single(Answer.Line(ControlText.statusHeader))
            .concat(Source(all.zip(stats)).mapAsync(1) { case (r, s) =>
              s.zip(holds).map { case (st, h) =>
                Answer.Line(ControlText.statusLine(r, st, h.find(_.robotId == r.robotId), servoLimits))
              }
            })
            .concat(Source.future(gameLines(gateway, settings.linkStatsTimeout, all)).mapConcat(_.map(Answer.Line(_))))
            .concat(Source.future(gameSource(gateway, settings.linkStatsTimeout)).mapConcat { source =>
              source.toList.flatMap(s =>
                (apps.StatusView.sourceLines(s) ++ apps.StatusView.monitorLines(s)).map(Answer.Line(_))) :+
                Answer.Ok(source.fold("")(_.describe))
            })
        }
      case Request.Call(id, module, method, params) =>
        val needs = Operation.RawCall(module, method, params).group
        val done = needs.fold(Future.successful(Done: Done))(g => robots.acquire(id, g)).flatMap { _ =>
          robots.call(id, module, method, params: _*).andThen { case _ => needs.foreach(g => robots.release(id, g)) }
        }
        Source.future(done).mapConcat { v =>
          List(Answer.Line(s"robot $id: $module.$method -> ${v.fold("(no value)")(_.toString)}"), Answer.Ok(""))
        }
      case Request.Doctor(_) =>
        gateway match {
          case None =>
            Source.single(Answer.Error("doctor needs the gateway's view, which this control port was not given"))
          case Some(g) =>
            Source.future(g.doctor().zip(holdFindings(robots))).mapConcat { case (checks, holds) =>
              val found = checks ++ holds
              val problems = found.count(_.problem)
              found.map(f => Answer.Line(f.line)) :+
                (if (problems == 0) Answer.Ok("all is well")
                 else Answer.Error(s"$problems problem(s), each with its fix above"))
            }
        }
      case Request.Servos(id) =>
        val limits = robotmiddleware.MiddlewareSettings(system).servoLimits
        Source.future(robots.robots()).mapConcat { all =>
          all.find(_.robotId == id) match {
            case None    => List(Answer.Error(RobotFailure.UnknownRobot(id).getMessage))
            case Some(r) => ControlText.servoLines(r, limits, System.nanoTime()).map(Answer.Line(_)) :+ Answer.Ok("")
          }
        }
      case Request.BatterySwap(id) =>
        gateway match {
          case None    => Source.single(Answer.Error(GatewaySide.notSimulated(id)))
          case Some(g) => Source.future(g.batterySwap(id)).map(Answer.Ok(_))
        }
      case Request.Watch(id, seconds) =>
        if (seconds.seconds > settings.maxWatch)
          Source.single(Answer.Error(s"a watch lasts at most ${settings.maxWatch.toSeconds} s"))
        else
          Source.future(robots.robots()).flatMapConcat { all =>
            if (!all.exists(_.robotId == id)) Source.failed(RobotFailure.UnknownRobot(id))
            else
              Source.single(Answer.Line(ControlText.statusHeader))
                .concat(
                  robots.status(id).takeWithin(seconds.seconds).map(s =>
                    Answer.Line(ControlText.statusLine(s, None, limits = servoLimits))))
                .concat(Source.single(Answer.Ok(s"watched robot $id for $seconds s")))
          }
    }
  }

  /** Where game state comes from, for the status's final line, with the message budget and the warnings for the lines
    * before it; none without a gateway or when it does not answer.
    */
  private def gameSource(gateway: Option[GatewaySide], timeout: FiniteDuration)(
      implicit system: ActorSystem[_]): Future[Option[GameSource]] = {
    implicit val ec: ExecutionContext = system.executionContext
    gateway.fold(Future.successful(Option.empty[GameSource])) { g =>
      within(g.view.gameSource(), timeout).map(Option(_)).recover { case NonFatal(_) => None }
    }
  }

  /** The game, the competition gate (with why a closed gate is closed) and each robot the GameController penalised, as
    * the status screen shows them, for the lines before the status's final one; none without a gateway or when it does
    * not answer.
    */
  private def gameLines(gateway: Option[GatewaySide], timeout: FiniteDuration, robots: Seq[RobotSnapshot])(
      implicit system: ActorSystem[_]): Future[List[String]] = {
    implicit val ec: ExecutionContext = system.executionContext
    gateway.fold(Future.successful(List.empty[String])) { g =>
      within(g.view.gameState(), timeout).zip(within(g.view.traffic(), timeout))
        .map { case (gm, t) =>
          List(apps.StatusView.gameLine(gm), apps.StatusView.gateLine(Some(t))) ++ robots.flatMap(r =>
            apps.StatusView.penalty(r, gm).map(p =>
              s"robot ${r.robotId} penalised by the GameController: ${p.describe}"))
        }
        .recover { case NonFatal(_) => Nil }
    }
  }

  /** `answer`, or a failure when it has not come within `timeout` (the view's own limit may be longer). */
  private def within[T](answer: Future[T], timeout: FiniteDuration)(implicit system: ActorSystem[_]): Future[T] =
    Future.firstCompletedOf(Seq(answer,
        akka.pattern.after(timeout)(Future.failed(new TimeoutException(s"no answer within $timeout")))))(
      ExecutionContext.parasitic)

  /** The robot's next link figures, or None when none come within `timeout`. */
  private def linkStats(robots: RobotInterface, robotId: Int, timeout: FiniteDuration)(
      implicit mat: Materializer): Future[Option[LinkStats]] =
    robots.linkStats(robotId).takeWithin(timeout).runWith(Sink.headOption).recover { case NonFatal(_) => None }(
      ExecutionContext.parasitic)

  /** One failed check per robot the middleware holds safe, with its reason (which says how the hold ends); one passed
    * check when none is held. None when the middleware does not answer (the other checks still come).
    */
  private def holdFindings(robots: RobotInterface)(implicit system: ActorSystem[_]): Future[Vector[Finding]] =
    within(robots.holds(), 3.seconds)
      .map(all => ControlText.holdFindings(all))(ExecutionContext.parasitic)
      .recover { case NonFatal(_) => Vector.empty }(ExecutionContext.parasitic)
}
