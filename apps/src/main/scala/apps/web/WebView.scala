package apps.web

import scala.concurrent.{ExecutionContext, Future}
import scala.util.{Failure, Success, Try}

import akka.NotUsed
import akka.actor.typed.scaladsl.{ActorContext, Behaviors, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior, PostStop}
import akka.stream.scaladsl.{BroadcastHub, Keep, Sink, Source}
import akka.stream.{BoundedSourceQueue, Materializer}

import naogateway.wire.gamecontroller.GameControlData
import naogateway.api.{GameSource, GatewayStats, RobotEvent, RobotLinks, RobotSnapshot, TrafficStats, VisionFrame}
import robotmiddleware.RobotMiddleware

/** The one owner of what the web view shows ([[WebModel]]). It asks the gateway's read-only view as the status view
  * does, and subscribes at the middleware to robot events and, while at least one page is connected, to each robot's
  * HaViMo2 frames (the camera costs the robots' WiFi budget: with no page open nobody asks for it); it asks for the
  * robots every `push-interval` while a page is open and for the gateway's other figures once a `sample-interval`;
  * every `push-interval` it renders one JSON push that every connected page shares (a broadcast hub, so the cost does
  * not grow with pages).
  */
object WebView {

  /** What the view accepts. */
  sealed trait Command

  /** Answers with what a new connection needs: its first message (every plot point, the whole log) and the pushes. */
  final case class Connect(replyTo: ActorRef[Feed]) extends Command

  /** A new connection's first message, and the shared pushes that follow (a connection buffers them itself). */
  final case class Feed(hello: String, pushes: Source[String, NotUsed])

  /** Answers with the figures of the pushes so far (for tests and the bench). */
  final case class GetFigures(replyTo: ActorRef[Figures]) extends Command

  /** Pushes rendered, pushes the shared queue had no room for, and the bytes of the last push. */
  final case class Figures(pushes: Long, dropped: Long, lastPushBytes: Int)

  private case object Tick extends Command
  private case object Sample extends Command
  private final case class Robots(robots: Vector[RobotSnapshot]) extends Command
  private final case class Links(links: RobotLinks) extends Command
  private final case class Traffic(stats: TrafficStats) extends Command
  private final case class Game(game: Option[GameControlData]) extends Command
  private final case class GameSourceIs(source: GameSource) extends Command
  private final case class Stats(stats: GatewayStats) extends Command
  // A question the gateway did not answer: the next tick asks again.
  private case object Unanswered extends Command
  private final case class Event(event: RobotEvent) extends Command
  private final case class Vision(frame: VisionFrame) extends Command
  private case object PageJoined extends Command
  private case object PageLeft extends Command

  /** The view's state between messages: the model, what the last push and grid carried, the pages connected, and the
    * camera watcher (a child that forwards frames, there while `pages > 0`; stopping it ends its watches, and the
    * robots switch the camera options off).
    */
  private final case class State(
      model: WebModel,
      pushedEvents: Long,
      pushedSamples: Long,
      answered: Boolean,
      watched: Set[Int],
      pages: Int,
      camera: Option[ActorRef[VisionFrame]],
      gridsSent: Map[Int, Long],
      gridsAtNanos: Long,
      pushedAtNanos: Long,
      figuresAskedAtNanos: Long,
      figures: Figures
  )

  /** The view of `gateway` and `middleware`'s robots with `settings`. */
  def apply(gateway: WebServer.GatewaySide, middleware: ActorRef[RobotMiddleware.Command],
      settings: WebSettings): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        implicit val mat: Materializer = Materializer(context)
        // The shared queue holds a few pushes; a push that finds it full is dropped (the next one carries the news).
        val (queue, hub) = Source.queue[String](4).toMat(BroadcastHub.sink[String](bufferSize = 16))(Keep.both).run()
        // One consumer that always reads, so the hub never holds pushes back for pages that join later.
        hub.runWith(Sink.ignore)
        // Without a page the view only keeps its plots' history: it asks the gateway once a sample and renders nothing.
        timers.startTimerWithFixedDelay(Tick, settings.sampleInterval)
        timers.startTimerWithFixedDelay(Sample, settings.sampleInterval)
        middleware ! RobotMiddleware.WatchEvents(context.messageAdapter(Event.apply))
        // The game comes as the GameController sends it, so a new state reaches the page at once, not at the next tick.
        middleware ! RobotMiddleware.WatchGame(context.messageAdapter((d: GameControlData) => Game(Some(d))))
        new View(gateway, middleware, settings, context, timers, queue, hub).running(State(
            WebModel(settings.historyPoints, settings.events,
              servoLimits = robotmiddleware.MiddlewareSettings(context.system).servoLimits),
            0L,
            0L,
            answered = true,
            Set.empty,
            0,
            None,
            Map.empty,
            0L,
            0L,
            Long.MinValue / 2,
            Figures(0, 0, 0)
          ))
      }
    }

  private final class View(gateway: WebServer.GatewaySide, middleware: ActorRef[RobotMiddleware.Command],
      settings: WebSettings,
      context: ActorContext[Command], timers: TimerScheduler[Command], queue: BoundedSourceQueue[String],
      hub: Source[String, NotUsed]) {
    private val started = System.nanoTime()
    private def ask[T](question: Future[T])(answer: T => Command): Unit =
      context.pipeToSelf(question) {
        case Success(a) => answer(a)
        case Failure(_) => Unanswered
      }

    // The view's own ref, for the page streams and the camera watcher (which must not touch this context).
    private val self = context.self

    private def t: Double = (System.nanoTime() - started) / 1e9

    /** Renders and offers one push; grids go along at most every `grid-interval`, and only those that changed. */
    private def push(s: State): State = {
      val now = System.nanoTime()
      val gridsDue = now - s.gridsAtNanos >= settings.gridInterval.toNanos
      val grids =
        if (!gridsDue) Set.empty[Int]
        else s.model.vision.collect {
          case (id, v) if v.grid.isDefined && !s.gridsSent.get(id).contains(v.gridFrame) => id
        }.toSet
      val newEvents = math.min(s.model.eventCount - s.pushedEvents, s.model.maxEvents.toLong).toInt
      val newSamples = math.min(s.model.sampleCount - s.pushedSamples, s.model.historyPoints.toLong).toInt
      val json = WebJson.push(s.model, t, newEvents, newSamples, grids, hello = false)
      val dropped = queue.offer(json) match {
        case akka.stream.QueueOfferResult.Enqueued => 0
        case _                                     => 1
      }
      s.copy(
        pushedEvents = s.model.eventCount,
        pushedSamples = s.model.sampleCount,
        answered = false,
        gridsSent = s.gridsSent ++ grids.map(id => id -> s.model.vision(id).gridFrame),
        gridsAtNanos = if (grids.nonEmpty) now else s.gridsAtNanos,
        pushedAtNanos = now,
        figures = Figures(s.figures.pushes + 1, s.figures.dropped + dropped, json.length)
      )
    }

    /** The state with `model`; when the model logged something new (a robot online or offline, a new game state), it is
      * pushed at once rather than at the next tick, yet never sooner than a fifth of `push-interval` after the last
      * push, so a burst of events cannot raise the rate above five times the configured one.
      */
    private def soon(s: State, model: WebModel): State = {
      val next = s.copy(model = model)
      if (s.pages > 0 && model
          .eventCount != s.model.eventCount && System.nanoTime() - s.pushedAtNanos >= settings.pushInterval.toNanos / 5)
        push(next)
      else next
    }

    /** The view with state `s`. */
    def running(s: State): Behavior[Command] = Behaviors.receiveMessage[Command] {
      case Tick =>
        ask(gateway.view.robots())(Robots.apply)
        // The links, the traffic (per-second figures), the game source and the gateway's counters are asked once a
        // sample, also while a page is open: asked at every push they would mostly answer what the last answer said.
        val now = System.nanoTime()
        val figuresDue = now - s.figuresAskedAtNanos >= settings.sampleInterval.toNanos * 9 / 10
        if (figuresDue) {
          ask(gateway.view.links())(Links.apply)
          ask(gateway.view.traffic())(Traffic.apply)
          ask(gateway.view.gameSource())(GameSourceIs.apply)
          ask(gateway.view.stats())(Stats.apply)
        }
        val asked = if (figuresDue) s.copy(figuresAskedAtNanos = now) else s
        // The push follows the robots' answer, so a page sees what the gateway saw within about one interval; when the
        // answer is late (a robot actor slow to answer), the next tick pushes what there is.
        running(if (s.answered || s.pages == 0) asked.copy(answered = false) else push(asked))
      case Robots(robots) =>
        // While a page is open, each robot's frames are watched from the first time it is listed (the middleware ends
        // the watch when the camera watcher stops).
        val fresh = s.camera.fold(Vector.empty[Int])(_ => robots.map(_.robotId).filterNot(s.watched))
        s.camera.foreach(camera =>
          fresh.foreach(id => middleware ! RobotMiddleware.WatchVision(id, camera, grid = true)))
        val signing = robots.map(r => r.robotId -> gateway.signing(r.robotId)).toMap
        val model = s.model.withRobots(robots).copy(signing = signing)
        val next = s.copy(model = model, watched = s.watched ++ fresh)
        running((if (s.pages > 0) push(next) else next).copy(answered = true))
      case Links(l)          => running(s.copy(model = s.model.withLinks(l.links, t, System.currentTimeMillis())))
      case Traffic(stats)    => running(s.copy(model = s.model.withTraffic(stats, t, System.currentTimeMillis())))
      case Game(game)        => running(soon(s, s.model.withGame(game, t, System.currentTimeMillis())))
      case GameSourceIs(src) => running(s.copy(model = s.model.copy(gameSource = Some(src))))
      case Stats(stats)      => running(s.copy(model = s.model.withGatewayStats(stats, t, System.currentTimeMillis())))
      case Event(event)      => running(soon(s, s.model.withEvent(event, t, System.currentTimeMillis())))
      case Vision(VisionFrame.Regions(id, frame, _, regions)) =>
        running(s.copy(model = s.model.withRegions(id, frame, regions)))
      case Vision(VisionFrame.Grid(id, frame, _, grid)) =>
        running(s.copy(model = s.model.withGrid(id, frame, grid.cells.toArray)))
      case Sample           => running(s.copy(model = s.model.sampled(t)))
      case Unanswered       => Behaviors.same
      case Connect(replyTo) =>
        // A page counts from when its stream runs until it ends, however it ends.
        val pushes = hub.watchTermination() { (_, done) =>
          self ! PageJoined
          done.onComplete(_ => self ! PageLeft)(ExecutionContext.parasitic)
          NotUsed
        }
        replyTo ! Feed(WebJson.push(s.model, t, s.model.maxEvents, s.model.historyPoints, s.model.vision.keySet,
            hello = true), pushes)
        Behaviors.same
      case PageJoined =>
        // The first page starts a camera watcher; the robots it knows are watched at the next answer of the gateway.
        val camera = s.camera.orElse(Some(context.spawnAnonymous(Behaviors.receiveMessage[VisionFrame] { frame =>
          self ! Vision(frame)
          Behaviors.same
        })))
        // The first page: the gateway is asked every push-interval again, starting now.
        if (s.pages == 0) {
          timers.startTimerWithFixedDelay(Tick, settings.pushInterval)
          self ! Tick
        }
        running(s.copy(pages = s.pages + 1, camera = camera))
      case PageLeft if s.pages > 1 => running(s.copy(pages = s.pages - 1))
      case PageLeft                =>
        // The last page left: the watcher stops, the middleware ends its watches, and the robots' cameras go quiet.
        s.camera.foreach(context.stop)
        timers.startTimerWithFixedDelay(Tick, settings.sampleInterval)
        running(s.copy(pages = 0, camera = None, watched = Set.empty))
      case GetFigures(replyTo) =>
        replyTo ! s.figures
        Behaviors.same
    }.receiveSignal { case (_, PostStop) =>
      // In a shutdown the actor system's materializer may have ended the stream first: then there is nothing to end.
      Try(queue.complete())
      Behaviors.same
    }
  }
}
