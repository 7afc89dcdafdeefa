package apps.web

import java.net.InetSocketAddress
import java.nio.charset.StandardCharsets
import java.security.MessageDigest
import java.util.concurrent.atomic.AtomicLong

import scala.concurrent.duration._
import scala.concurrent.{ExecutionContext, Future}
import scala.util.{Failure, Success}

import akka.NotUsed
import akka.actor.typed.scaladsl.AskPattern._
import akka.actor.typed.scaladsl.{ActorContext, Behaviors}
import akka.actor.typed.{ActorRef, ActorSystem, Behavior, PostStop}
import akka.http.scaladsl.Http
import akka.http.scaladsl.model.ws.{BinaryMessage, Message, TextMessage}
import akka.http.scaladsl.model.StatusCodes
import akka.http.scaladsl.server.Directives._
import akka.http.scaladsl.server.{Directive0, Route}
import akka.stream.scaladsl.{Flow, Sink, Source}
import akka.stream.{BufferOverflowException, Materializer, OverflowStrategy}
import akka.util.Timeout
import org.slf4j.LoggerFactory

import naogateway.api.GatewayView
import naogateway.transport.RateLimitedLog
import robotmiddleware.RobotMiddleware

/** The web view's HTTP server (docs/web.md): the page and its assets from the jar, and the WebSocket `/ws` that carries
  * [[WebView]]'s pushes. Every connection buffers at most `client-buffer` pushes; one that falls further behind (a page
  * that stopped reading) is disconnected, so a slow phone costs a bounded amount of memory.
  */
object WebServer {

  /** What the server accepts. */
  sealed trait Command

  /** Answers with the bound address (the real port when 0 was configured) once bound, or None if it did not bind. */
  final case class GetAddress(replyTo: ActorRef[Option[InetSocketAddress]]) extends Command

  /** Answers with the connection figures. */
  final case class GetCounters(replyTo: ActorRef[Counters]) extends Command

  /** Connections now, connections refused (too many, or a wrong token), slow clients dropped, frames from pages
    * ignored, and WebSocket handshakes refused for their `Origin` ([[WebOrigin.check]]).
    */
  final case class Counters(open: Long, refused: Long, slowDropped: Long, ignoredFrames: Long, originRefused: Long = 0)

  private final case class Bound(binding: Http.ServerBinding) extends Command
  private final case class BindFailed(reason: Throwable) extends Command

  /** The page and its assets: resource paths in the jar, by the path the page asks for. */
  private[web] lazy val Assets: Map[String, String] = Map(
    "app.js" -> "apps/web/app.js",
    "app.css" -> "apps/web/app.css",
    "control.js" -> "apps/web/control.js",
    "uPlot.iife.min.js" -> s"META-INF/resources/webjars/uplot/$uplotVersion/dist/uPlot.iife.min.js",
    "uPlot.min.css" -> s"META-INF/resources/webjars/uplot/$uplotVersion/dist/uPlot.min.css"
  )

  /** The address line the launcher shows: where the page is, with its token when one is set. */
  def describe(address: InetSocketAddress, settings: WebSettings): String = {
    val host = address.getAddress match {
      case a if a.isAnyLocalAddress => "127.0.0.1"
      case a: java.net.Inet6Address => s"[${a.getHostAddress}]"
      case a                        => a.getHostAddress
    }
    s"web view: http://$host:${address.getPort}/" + (if (settings.token.nonEmpty) "?token=<apps.web.token>" else "")
  }

  /** What the web view reads of the gateway, handed in by the launcher: its read-only view, whether the competition
    * mode is on (which refuses the control panel), and each robot's signing rule by name.
    */
  final case class GatewaySide(view: GatewayView, competition: Boolean, signing: Int => String)

  /** Spawns the server (and its view) as a child of `context` when `apps.web.enabled` opens it ([[apps.Doors.open]]:
    * `auto` keeps it shut while `realRobots`) and its settings may serve (a token off loopback).
    */
  def spawnIfEnabled(context: ActorContext[_], gateway: GatewaySide, middleware: ActorRef[RobotMiddleware.Command],
      realRobots: Boolean, bound: Option[InetSocketAddress] => Unit = _ => ()): Option[ActorRef[Command]] = {
    val settings = WebSettings(context.system)
    if (!apps.Doors.open(settings.enabled, realRobots)) None
    else settings.refusal match {
      case Some(reason) =>
        context.log.error("Web view not started: {}", reason)
        None
      case None => Some(context.spawn(apply(gateway, middleware, settings, bound), "web"))
    }
  }

  /** The server of `gateway`'s and `middleware`'s view; `bound` hears the address once (None if it did not bind). */
  def apply(gateway: GatewaySide, middleware: ActorRef[RobotMiddleware.Command], settings: WebSettings,
      bound: Option[InetSocketAddress] => Unit = _ => ()): Behavior[Command] =
    Behaviors.setup { context =>
      require(settings.refusal.isEmpty, settings.refusal.getOrElse(""))
      implicit val system: ActorSystem[_] = context.system
      val view = context.spawn(WebView(gateway, middleware, settings), "view")
      val foxglove = context.spawn(FoxgloveFeed(middleware, gateway.view), "foxglove")
      val available = availability(settings, gateway.competition)
      if (settings.control.enabled && !available.enabled)
        context.log.warn("Web control panel refused: {}", available.reason)
      val control = context.spawn(WebControl(middleware, settings.control, available), "control")
      val connections = new Connections(settings)
      context.pipeToSelf(Http().newServerAt(settings.bindAddress, settings.port)
          .bind(routes(view, foxglove, control, available, settings, connections))) {
        case Success(b) => Bound(b)
        case Failure(e) => BindFailed(e)
      }
      Behaviors.withStash(16) { stash =>
        Behaviors.receiveMessage {
          case Bound(binding) =>
            bound(Some(binding.localAddress))
            context.log.info(describe(binding.localAddress, settings))
            if (!binding.localAddress.getAddress.isLoopbackAddress)
              context.log.warn(
                "Web view {} is not on loopback: every machine that reaches it and has the token can " +
                  "watch the robots{}",
                binding.localAddress,
                if (available.enabled) " and steer them from the control panel" else ""
              )
            stash.unstashAll(serving(binding, connections))
          case BindFailed(e) =>
            bound(None)
            context.log.error(s"Web view: cannot listen on ${settings.bindAddress}:${settings.port}: ${e.getMessage}")
            stash.unstashAll(Behaviors.receiveMessage {
              case GetAddress(replyTo)  => replyTo ! None; Behaviors.same
              case GetCounters(replyTo) => replyTo ! connections.counters; Behaviors.same
              case _                    => Behaviors.same
            })
          case other =>
            if (!stash.isFull) stash.stash(other)
            Behaviors.same
        }
      }
    }

  private def serving(binding: Http.ServerBinding, connections: Connections): Behavior[Command] =
    Behaviors.receiveMessage[Command] {
      case GetAddress(replyTo)  => replyTo ! Some(binding.localAddress); Behaviors.same
      case GetCounters(replyTo) => replyTo ! connections.counters; Behaviors.same
      case _                    => Behaviors.same
    }.receiveSignal { case (_, PostStop) =>
      binding.terminate(1.second)
      Behaviors.same
    }

  /** The connection counters, shared by the connections' streams (so atomic), and the rules they apply. */
  private[web] final class Connections(settings: WebSettings) {
    val open = new AtomicLong
    val refused = new AtomicLong
    val slowDropped = new AtomicLong
    val ignored = new AtomicLong
    val originRefused = new AtomicLong
    private val log = LoggerFactory.getLogger("apps.web.WebServer")
    private val allowed = settings.allowedOrigins.flatMap(WebOrigin.parse)

    /** The counters now. */
    def counters: Counters = Counters(open.get, refused.get, slowDropped.get, ignored.get, originRefused.get)

    /** The verdict on a WebSocket handshake's `Origin`; a refusal is counted and logged at a bounded rate. */
    def originOk(origin: Option[String], host: Option[String], scheme: String): Boolean =
      WebOrigin.check(origin, host, scheme, allowed, settings.token.nonEmpty) match {
        case WebOrigin.Allowed => true
        case WebOrigin.Refused(reason) =>
          val n = originRefused.incrementAndGet()
          if (RateLimitedLog.due(n))
            log.warn("Web view: WebSocket refused: {} ({} refused for their origin so far)", reason, n)
          false
      }

    /** Whether `presented` is the token (compared in constant time); any string passes when none is configured. */
    def tokenOk(presented: Option[String]): Boolean =
      settings.token.isEmpty || presented.exists(g =>
        MessageDigest.isEqual(g.getBytes(StandardCharsets.UTF_8), settings.token.getBytes(StandardCharsets.UTF_8)))

    /** Takes a connection slot, or counts a refusal when all `max-clients` are taken. */
    def admit(): Boolean =
      if (open.incrementAndGet() <= settings.maxClients) true
      else {
        open.decrementAndGet()
        val n = refused.incrementAndGet()
        if (RateLimitedLog.due(n))
          log.warn("Web view: connection refused, {} open already ({} refused so far)", settings.maxClients, n)
        false
      }

    /** Counts a connection refused for its token, logged at a bounded rate. */
    def refuse(): Unit = {
      val n = refused.incrementAndGet()
      if (RateLimitedLog.due(n)) log.warn("Web view: connection without the right token refused ({} refused so far)", n)
    }

    /** A connection ended; a slow one (its buffer overflowed) is counted and logged at a bounded rate. */
    def closed(failure: Option[Throwable]): Unit = {
      open.decrementAndGet()
      failure.foreach {
        case _: BufferOverflowException =>
          val n = slowDropped.incrementAndGet()
          if (RateLimitedLog.due(n)) log.warn("Web view: a client that did not read was disconnected ({} so far)", n)
        case _ => ()
      }
    }

    /** What comes from a page is read and dropped (the view is read-only): counted, never kept. */
    def ignore(message: Message)(implicit mat: Materializer): Unit = {
      ignored.incrementAndGet()
      message match {
        case t: TextMessage   => t.textStream.runWith(Sink.ignore)
        case b: BinaryMessage => b.dataStream.runWith(Sink.ignore)
      }
      ()
    }
  }

  /** Whether the control panel may serve: enabled, a token set, and not in competition mode. */
  def availability(settings: WebSettings, competition: Boolean): WebControl.Availability =
    if (!settings.control.enabled)
      WebControl.Availability(enabled = false, "the control panel is off (apps.web.control.enabled)")
    else if (competition) WebControl.Availability(enabled = false,
      "the control panel is refused in competition mode (naogateway.competition.enabled)")
    else if (settings.token.isEmpty)
      WebControl.Availability(enabled = false, "the control panel needs an access token (apps.web.token)")
    else WebControl.Availability(enabled = true, "on")

  private[web] def routes(view: ActorRef[WebView.Command], foxglove: ActorRef[FoxgloveFeed.Command],
      control: ActorRef[WebControl.Command],
      available: WebControl.Availability, settings: WebSettings, connections: Connections)(
      implicit system: ActorSystem[_]): Route = {
    implicit val timeout: Timeout = Timeout(3.seconds)
    implicit val ec: ExecutionContext = system.executionContext
    val loader = getClass.getClassLoader
    concat(
      pathSingleSlash {
        get(getFromResource("apps/web/index.html", akka.http.scaladsl.model.ContentTypes.`text/html(UTF-8)`, loader))
      },
      path("assets" / Segment) { name =>
        Assets.get(name).fold[Route](complete(StatusCodes.NotFound))(resource =>
          get(getFromResource(resource, akka.http.scaladsl.server.directives.ContentTypeResolver.Default(resource),
              loader)))
      },
      path("foxglove")(sameOrigin(connections)(foxgloveRoute(foxglove, settings, connections))),
      path("control" / "state") {
        get(complete(akka.http.scaladsl.model.HttpEntity(
              akka.http.scaladsl.model.ContentTypes.`application/json`,
              spray.json.JsObject("enabled" -> spray.json.JsBoolean(available.enabled),
                "reason" -> spray.json.JsString(available.reason)).compactPrint
            )))
      },
      path("control")(sameOrigin(connections)(controlRoute(control, available, connections))),
      path("ws") {
        (sameOrigin(connections) & extractWebSocketUpgrade & parameter("token".optional)) { (upgrade, token) =>
          if (!connections.tokenOk(token)) {
            connections.refuse()
            complete(StatusCodes.Forbidden, "a valid token is needed: open the page as /?token=...")
          } else if (!connections.admit()) complete(StatusCodes.ServiceUnavailable, "too many pages open")
          else {
            val flow: Future[Flow[Message, Message, NotUsed]] =
              view.ask(WebView.Connect(_)).map(feed => pageFlow(feed, settings, connections))
                .recover { case _ =>
                  // The view did not answer (it is stopping): the slot is given back and the connection closes.
                  connections.closed(None)
                  Flow.fromSinkAndSource(Sink.ignore, Source.empty)
                }
            complete(upgrade.handleMessages(Flow.futureFlow(flow).mapMaterializedValue(_ => NotUsed)))
          }
        }
      }
    )
  }

  /** Passes a request whose `Origin` the rule allows ([[WebOrigin.check]]); any other is answered 403 before its
    * WebSocket opens, so a page of another site cannot read a feed or make the view watch a camera.
    */
  private def sameOrigin(connections: Connections): Directive0 =
    (optionalHeaderValueByName("Origin") & optionalHeaderValueByName("Host") & extractUri).tflatMap {
      case (origin, host, uri) =>
        if (connections.originOk(origin, host, uri.scheme)) pass
        else complete(StatusCodes.Forbidden, "this WebSocket is for the web view's own page (apps.web.allowed-origins)")
    }

  /** The Foxglove-protocol feed (`/foxglove`, subprotocol foxglove.sdk.v1 or foxglove.websocket.v1, answered with the
    * one the client asked for), behind the same origin rule, token and limits.
    */
  private def foxgloveRoute(foxglove: ActorRef[FoxgloveFeed.Command], settings: WebSettings, connections: Connections)(
      implicit
      system: ActorSystem[_]): Route = {
    implicit val timeout: Timeout = Timeout(FoxgloveFeed.ConnectTimeout)
    implicit val ec: ExecutionContext = system.executionContext
    (extractWebSocketUpgrade & parameter("token".optional)) { (upgrade, token) =>
      val subprotocol = FoxgloveFeed.chosen(upgrade.requestedProtocols)
      if (subprotocol.isEmpty)
        complete(StatusCodes.BadRequest,
          s"this feed speaks the WebSocket subprotocols ${FoxgloveFeed.Subprotocols.mkString(" and ")}")
      else if (!connections.tokenOk(token)) {
        connections.refuse()
        complete(StatusCodes.Forbidden, "a valid token is needed: /foxglove?token=...")
      } else if (!connections.admit()) complete(StatusCodes.ServiceUnavailable, "too many clients connected")
      else {
        val flow: Future[Flow[Message, Message, NotUsed]] = foxglove.ask(FoxgloveFeed.Connect(_))
          .map(feed =>
            FoxgloveFeed.connection(feed, settings.clientBuffer, () => { connections.ignored.incrementAndGet(); () })
              .watchTermination() { (_, done) =>
                done.onComplete {
                  case Success(_) => connections.closed(None)
                  case Failure(e) => connections.closed(Some(e))
                }
                NotUsed
              })
          .recover { case _ =>
            connections.closed(None)
            Flow.fromSinkAndSource(Sink.ignore, Source.empty)
          }
        complete(upgrade.handleMessages(Flow.futureFlow(flow).mapMaterializedValue(_ => NotUsed),
            subprotocol))
      }
    }
  }

  /** The control panel's WebSocket (`/control`): one JSON request in, one JSON answer out; only with the token. */
  private def controlRoute(control: ActorRef[WebControl.Command], available: WebControl.Availability,
      connections: Connections)(implicit
      system: ActorSystem[_]): Route = {
    implicit val timeout: Timeout = Timeout(WebControl.RequestTimeout)
    (extractWebSocketUpgrade & parameter("token".optional)) { (upgrade, token) =>
      if (!available.enabled) complete(StatusCodes.Forbidden, available.reason)
      else if (!connections.tokenOk(token)) {
        connections.refuse()
        complete(StatusCodes.Forbidden, "a valid token is needed: /control?token=...")
      } else if (!connections.admit()) complete(StatusCodes.ServiceUnavailable, "too many clients connected")
      else {
        val flow = Flow[Message]
          .mapAsync(1) {
            case t: TextMessage =>
              t.textStream.limitWeighted(4096L)(_.length.toLong).runFold(new StringBuilder)(_ append _)
                .flatMap(text => control.ask[String](WebControl.Request(WebControl.drive(text.toString), _)))(
                  system.executionContext)
            case b: BinaryMessage =>
              b.dataStream.runWith(Sink.ignore)
              Future.successful("""{"op":"result","ok":false,"message":"the control panel takes JSON text"}""")
          }
          .map(TextMessage.Strict(_): Message)
          .watchTermination() { (_, done) =>
            done.onComplete {
              case Success(_) => connections.closed(None)
              case Failure(e) => connections.closed(Some(e))
            }(system.executionContext)
            NotUsed
          }
        complete(upgrade.handleMessages(flow))
      }
    }
  }

  /** One page's connection: its first message, then the shared pushes through its own bounded buffer. */
  private def pageFlow(feed: WebView.Feed, settings: WebSettings, connections: Connections)(
      implicit mat: Materializer): Flow[Message, Message, NotUsed] = {
    val out: Source[Message, NotUsed] = feed.pushes
      .buffer(settings.clientBuffer, OverflowStrategy.fail)
      .prepend(Source.single(feed.hello))
      .map(TextMessage.Strict(_): Message)
      .watchTermination() { (_, done) =>
        done.onComplete {
          case Success(_) => connections.closed(None)
          case Failure(e) => connections.closed(Some(e))
        }(mat.executionContext)
        NotUsed
      }
    Flow.fromSinkAndSourceCoupled(Sink.foreach[Message](connections.ignore), out)
  }

  /** The version of the uPlot jar on the classpath, from its Maven metadata (the version is pinned in the build only).
    */
  private[web] lazy val uplotVersion: String = {
    val props = new java.util.Properties
    val in = getClass.getClassLoader.getResourceAsStream("META-INF/maven/org.webjars.npm/uplot/pom.properties")
    require(in != null, "the uPlot jar is not on the classpath")
    try props.load(in)
    finally in.close()
    props.getProperty("version")
  }
}
