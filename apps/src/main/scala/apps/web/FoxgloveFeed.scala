package apps.web

import java.nio.{ByteBuffer, ByteOrder}
import java.nio.charset.StandardCharsets
import java.util.Base64

import scala.concurrent.ExecutionContext
import scala.concurrent.duration._
import scala.util.{Failure, Success, Try}

import akka.NotUsed
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, Behavior, PostStop}
import akka.http.scaladsl.model.ws.{BinaryMessage, Message, TextMessage}
import akka.stream.scaladsl.{BroadcastHub, Flow, Keep, Sink, Source}
import akka.stream.{BoundedSourceQueue, Materializer, OverflowStrategy}
import akka.util.ByteString
import spray.json._

import naogateway.proto.RecordedPort
import naogateway.wire.{MessageContents, RpcReply}
import naogateway.wire.gamecontroller.GameControlData
import naogateway.api.{GameStateUpdated, GatewayView, RobotEvent, RobotOnline, RobotSnapshot, TrafficStats}
import naogateway.api.recording.{
  Decision,
  DecisionJson,
  GatewayTap,
  RecordEncoder,
  RecordingSchema,
  TapSubscription,
  Tapped
}
import robotmiddleware.RobotMiddleware

/** The live feed in the Foxglove WebSocket protocol (subprotocol `foxglove.sdk.v1` of the Foxglove SDK, or
  * `foxglove.websocket.v1` of the earlier ws-protocol; docs/web.md): every channel of the recording with its schema.
  * `/robot/<id>/status`, `/robot/<id>/health` and `/robot/<id>/servos` (each new servo telemetry, docs/protocol.md 6.8)
  * come from the middleware's robot snapshots; `/gateway/datagrams` and `/robot/<id>/message` from the gateway's tap,
  * as the recorder reads them; `/gateway/decisions` (JSON, as recorded) carries robot events and game states from the
  * middleware, the budget once a second from the gateway's read-only view, and the outbox's sends, the gate and the
  * robots' replies from the tap. A viewer connected to the running gateway shows what it shows for a recording. Each
  * keep-alive is published as the gateway read it ([[naogateway.wire.RobotReport]], the one mapping between the
  * messages and a robot's report).
  */
object FoxgloveFeed {

  /** The subprotocol of the Foxglove WebSocket protocol as the ws-protocol libraries name it. */
  val Subprotocol: String = "foxglove.websocket.v1"

  /** The same protocol as the Foxglove SDK's servers name it (and Foxglove's and Lichtblick's current viewers ask). The
    * SDK's message set is the ws-protocol's; the part this feed uses (server info, status, advertise, subscribe,
    * unsubscribe, message data) reads the same under both names.
    */
  val SdkSubprotocol: String = "foxglove.sdk.v1"

  /** Every name the feed answers to, the one it prefers first. */
  val Subprotocols: Vector[String] = Vector(SdkSubprotocol, Subprotocol)

  /** The subprotocol to answer a client that asked for `requested`: the SDK's name when offered, else the
    * ws-protocol's; None when it offered neither.
    */
  def chosen(requested: Seq[String]): Option[String] = Subprotocols.find(p => requested.exists(_.trim == p))

  /** One channel as advertised: its id, topic, schema name and message encoding (the schema data of a protobuf channel
    * is the recording's descriptor set; a JSON channel has none, as in the recording).
    */
  final case class Channel(id: Int, topic: String, schemaName: String, encoding: String = "protobuf")

  /** A robot's channels, and when the servo telemetry last published was received (`RobotSnapshot.servos`). */
  private final case class RobotChannels(status: Channel, health: Channel, servos: Channel, message: Channel,
      servosAt: Option[Long])

  /** The gateway's decisions as the recording writes them (JSON without a schema). */
  private[web] val Decisions: Channel = Channel(1, RecordingSchema.Topics.Decisions, "", "json")

  /** Every datagram that crossed the gateway's ports, as the recording writes it. */
  private[web] val Datagrams: Channel =
    Channel(2, RecordingSchema.Topics.Datagrams, "naogateway.proto.RecordedDatagram")

  /** What the feed's hub hands its connections: channels appearing, and messages on them. */
  sealed trait Update

  /** New channels, to be advertised to every connection. */
  final case class Advertised(channels: Vector[Channel]) extends Update

  /** A message on a channel, at `nanos` (the gateway's wall clock), for the connections subscribed to it. It names its
    * channel whole, so a connection that joined the hub just after the channel was advertised still learns of it.
    */
  final case class Published(channel: Channel, nanos: Long, bytes: Array[Byte]) extends Update

  /** What the feed accepts. */
  sealed trait Command

  /** Answers with the channels so far and the updates that follow. */
  final case class Connect(replyTo: ActorRef[Feed]) extends Command

  /** A connection's start: the channels known now, then the shared updates. */
  final case class Feed(channels: Vector[Channel], updates: Source[Update, NotUsed])

  private final case class Status(snapshot: RobotSnapshot) extends Command
  private final case class Event(event: RobotEvent) extends Command
  private final case class Game(data: GameControlData) extends Command
  private final case class Traffic(stats: TrafficStats) extends Command
  // The gateway did not answer a question: the next tick asks again.
  private case object Unanswered extends Command
  private case object BudgetTick extends Command
  // A connection's updates began or ended: with none, nothing is encoded or asked for.
  private case object ClientJoined extends Command
  private case object ClientLeft extends Command
  // The gateway's tap, to read while clients are connected; and the tick that reads it (a single timer each time, at
  // the pace the last read calls for).
  private final case class TapAnswered(tap: GatewayTap) extends Command
  private case object TapTick extends Command

  /** How often the budget decision is published (the recording's outbox writes it at most this often). */
  private val BudgetInterval: FiniteDuration = 1.second

  /** The tap's fastest pace while clients are connected: while ticks find it full the feed reads it this often. */
  private[web] val TapIntervalMin: FiniteDuration = 50.millis

  /** The tap's slowest pace: while ticks find little or nothing the feed reads it this often (the page's push pace), so
    * a quiet gateway wakes the feed four times a second, not twenty.
    */
  private[web] val TapIntervalMax: FiniteDuration = 250.millis

  /** The feed's queue at the gateway's tap; what does not fit is dropped and counted there (`GatewayStats.tap`). */
  private[web] val TapCapacity: Int = 4096

  /** Tap entries published per tick at most (about 1300 a second at the fastest pace): a burst reaches no client's
    * buffer whole (16 times `client-buffer`, which would close the connection); the rest waits at the tap, and what no
    * longer fits is dropped there and counted.
    */
  private[web] val TapEntriesPerTick: Int = 64

  /** The pace after a tick that read `found` entries at pace `current`: the fastest after a full tick (entries wait),
    * twice as slow (up to the slowest) after one that found less than half a tick's worth, else the same. Bounded both
    * ways: it never spins, and a backlog is read at the fastest pace from the next tick on.
    */
  private[web] def nextTapInterval(current: FiniteDuration, found: Int): FiniteDuration =
    if (found >= TapEntriesPerTick) TapIntervalMin
    else if (found < TapEntriesPerTick / 2) (current * 2).min(TapIntervalMax)
    else current

  /** The feed's name among the tap's readers. */
  val TapReader: String = "foxglove-feed"

  /** What the hub knows: each robot's channels, every channel advertised, the clients, the tap while it reads it, and
    * the status watcher (a child forwarding the middleware's snapshots, there while a client is connected).
    */
  private final case class State(robots: Map[Int, RobotChannels], channels: Vector[Channel], clients: Int,
      tap: Option[TapSubscription], askingTap: Boolean, statusWatcher: Option[ActorRef[RobotSnapshot]],
      tapInterval: FiniteDuration)

  /** The hub: one owner of the channel list, watching robot events and the game at the middleware, and while any client
    * is connected watching the robots' snapshots, asking `gateway` for the budget and reading the gateway's tap
    * (datagrams, robot messages, the outbox's and the gate's decisions). Without a client a robot's channels are made
    * when it comes online, so nothing wakes the feed for a keep-alive.
    */
  def apply(middleware: ActorRef[RobotMiddleware.Command], gateway: GatewayView): Behavior[Command] =
    Behaviors.setup { context =>
      implicit val mat: Materializer = Materializer(context)
      val (queue, hub) = Source.queue[Update](1024).toMat(BroadcastHub.sink[Update](bufferSize = 64))(Keep.both).run()
      hub.runWith(Sink.ignore)
      middleware ! RobotMiddleware.WatchEvents(context.messageAdapter(Event.apply))
      middleware ! RobotMiddleware.WatchGame(context.messageAdapter(Game.apply))
      val self = context.self
      // The hub's scratch, used on its own turn only: the entries taken from the tap at a tick, and their encoder.
      val taken = new java.util.ArrayList[Tapped](TapEntriesPerTick)
      val encoder = new RecordEncoder

      Behaviors.withTimers[Command] { timers =>
        timers.startTimerWithFixedDelay(BudgetTick, BudgetInterval)

        def askTap(state: State): State =
          if (state.tap.isDefined || state.askingTap) state
          else {
            context.pipeToSelf(gateway.tap()) {
              case Success(t) => TapAnswered(t)
              case Failure(_) => Unanswered
            }
            state.copy(askingTap = true)
          }

        /** Robot `id`'s channels, made (and advertised) when first needed while there is room. */
        def robotChannels(state: State, id: Int): (Option[RobotChannels], State) =
          state.robots.get(id) match {
            case some @ Some(_) => (some, state)
            /* As in a recording, at most MaxRobotChannels robots get channels: a flood of robot ids cannot grow the
             * list. */
            case None if state.robots.size >= RecordingSchema.MaxRobotChannels => (None, state)
            case None =>
              val n = state.channels.size
              val robot = RobotChannels(
                Channel(n + 1, RecordingSchema.Topics.status(id), "naogateway.proto.Status"),
                Channel(n + 2, RecordingSchema.Topics.health(id), "naogateway.proto.RobotHealth"),
                Channel(n + 3, RecordingSchema.Topics.servos(id), "naogateway.proto.ServoTelemetry"),
                Channel(n + 4, RecordingSchema.Topics.message(id), "naogateway.proto.Message"),
                None
              )
              val more = Vector(robot.status, robot.health, robot.servos, robot.message)
              queue.offer(Advertised(more))
              (Some(robot), state.copy(robots = state.robots.updated(id, robot), channels = state.channels ++ more))
          }

        /** The entries waiting at the tap (at most a tick's worth), on the recording's channels. */
        def readTap(state: State, tap: TapSubscription): State = {
          taken.clear()
          val found = tap.drainTo(taken, TapEntriesPerTick)
          val pace = nextTapInterval(state.tapInterval, found)
          timers.startSingleTimer(TapTick, pace)
          // The gateway's wall clock of a System.nanoTime, as the recorder dates its messages.
          val epochOffset = System.currentTimeMillis() * 1000000L - System.nanoTime()
          var next = state.copy(tapInterval = pace)
          var i = 0
          while (i < taken.size) {
            taken.get(i) match {
              case d: Tapped.Datagram =>
                val nanos = epochOffset + d.nanoTime
                val n = encoder.datagram(d, RecordEncoder.addressBytes(d.source),
                  RecordEncoder.addressBytes(d.destination))
                queue.offer(Published(Datagrams, nanos, java.util.Arrays.copyOf(encoder.bytes, n)))
                if (d.port == RecordedPort.ROBOT_PORT && d.received) next = robotMessage(next, d.decoded, nanos)
              case Tapped.Decided(at, decision) =>
                decision match {
                  // Published events and the budget come from the middleware and the gateway's figures, also while
                  // the tap carries none of them (they reach the tap only while recording).
                  case _: Decision.Published | _: Decision.Budget => ()
                  case other                                      => decided(queue, other, epochOffset + at)
                }
            }
            i += 1
          }
          taken.clear()
          next
        }

        /** A robot's frame on its message channel when it holds more than a keep-alive, and a reply as a decision: only
          * a frame the gateway accepted (the port's reader decoded it); a stranger's stays on /gateway/datagrams.
          */
        def robotMessage(state: State, decoded: Option[MessageContents], nanos: Long): State =
          decoded match {
            case Some(c) =>
              val onChannel = RecordEncoder.onMessageChannel(c)
              val (robot, next) = if (onChannel) robotChannels(state, c.robotId) else (None, state)
              robot.foreach(r => queue.offer(Published(r.message, nanos, c.toProtobuf)))
              c.rpcResponse.foreach { r =>
                queue.offer(Published(Decisions, nanos,
                    DecisionJson.reply(c.robotId, RpcReply.fromProto(r), nanos).getBytes(StandardCharsets.UTF_8)))
              }
              next
            case None => state // on /gateway/datagrams only; the gateway counted the refusal
          }

        def running(state: State): Behavior[Command] =
          Behaviors.receiveMessage[Command] {
            case Connect(replyTo) =>
              val updates = hub.watchTermination() { (_, done) =>
                self ! ClientJoined
                done.onComplete(_ => self ! ClientLeft)(ExecutionContext.parasitic)
                NotUsed
              }
              replyTo ! Feed(state.channels, updates)
              Behaviors.same
            case ClientJoined =>
              // The first client: the robots' snapshots are watched (the current ones first) until the last leaves.
              val watcher = state.statusWatcher.getOrElse {
                val w = context.spawnAnonymous(Behaviors.receiveMessage[RobotSnapshot] { snapshot =>
                  self ! Status(snapshot)
                  Behaviors.same
                })
                middleware ! RobotMiddleware.WatchStatus(None, w)
                w
              }
              running(askTap(state.copy(clients = state.clients + 1, statusWatcher = Some(watcher))))
            case ClientLeft =>
              val clients = math.max(0, state.clients - 1)
              if (clients > 0) running(state.copy(clients = clients))
              else {
                // No client: off the tap, so the gateway builds nothing for the feed, and off the snapshots (the
                // middleware ends the watch of a watcher that stopped).
                state.tap.foreach(_.close())
                timers.cancel(TapTick)
                state.statusWatcher.foreach(context.stop)
                running(state.copy(clients = 0, tap = None, statusWatcher = None))
              }
            case TapAnswered(tap) =>
              if (state.clients == 0) running(state.copy(askingTap = false))
              else {
                // Each tick sets the next one at the pace what it found calls for (nextTapInterval).
                timers.startSingleTimer(TapTick, TapIntervalMin)
                running(state.copy(tap = Some(tap.subscribe(TapReader, TapCapacity)), askingTap = false,
                    tapInterval = TapIntervalMin))
              }
            case TapTick =>
              state.tap.fold(Behaviors.same[Command])(t => running(readTap(state, t)))
            case Event(event) =>
              if (state.clients > 0) decided(queue, Decision.Published(event), nowNanos())
              event match {
                // A robot online gets its channels, so the list is whole for the next client without watching
                // keep-alives.
                case RobotOnline(id, _) =>
                  val (_, next) = robotChannels(state, id)
                  if (next eq state) Behaviors.same else running(next)
                case _ => Behaviors.same
              }
            case Game(data) =>
              if (state.clients > 0) decided(queue, Decision.Published(GameStateUpdated(data)), nowNanos())
              Behaviors.same
            case BudgetTick =>
              if (state.clients > 0) {
                context.pipeToSelf(gateway.traffic()) {
                  case Success(t) => Traffic(t)
                  case Failure(_) => Unanswered
                }
                // A tap the gateway did not hand over: asked again.
                running(askTap(state))
              } else Behaviors.same
            case Unanswered =>
              if (state.askingTap && state.tap.isEmpty) running(state.copy(askingTap = false)) else Behaviors.same
            case Traffic(t) =>
              decided(queue,
                Decision.Budget(t.outBytesLastSecond, t.inBytesLastSecond, t.budgetBytesPerSecond, t.queued),
                nowNanos())
              Behaviors.same
            case Status(snapshot) =>
              val (known, next) = robotChannels(state, snapshot.robotId)
              known.fold(Behaviors.same[Command]) { robot =>
                // Each telemetry once, as the robot sent it: the snapshot keeps it over keep-alives without one.
                val servosAt = snapshot.servos.map(_.receivedAtNanos)
                if (next.clients > 0) {
                  val nanos = nowNanos()
                  val report = snapshot.report
                  queue.offer(Published(robot.status, nanos, report.status.toByteArray))
                  queue.offer(Published(robot.health, nanos, report.health.toByteArray))
                  snapshot.servos.filter(_ => servosAt != robot.servosAt).foreach(t =>
                    queue.offer(Published(robot.servos, nanos, t.toProto.toByteArray)))
                }
                val seen = if (next.clients > 0) servosAt else robot.servosAt
                if ((next eq state) && seen == robot.servosAt) Behaviors.same
                else running(next.copy(robots = next.robots.updated(snapshot.robotId, robot.copy(servosAt = seen))))
              }
          }.receiveSignal { case (_, PostStop) =>
            state.tap.foreach(_.close())
            // In a shutdown the actor system's materializer may have ended the stream first: then there is nothing to
            // end.
            Try(queue.complete())
            Behaviors.same
          }

        running(State(Map.empty, Vector(Decisions, Datagrams), clients = 0, tap = None, askingTap = false,
            statusWatcher = None, tapInterval = TapIntervalMin))
      }
    }

  private def nowNanos(): Long = System.currentTimeMillis() * 1000000L

  /** `decision` on the decisions channel at `nanos`, in the recording's JSON. */
  private def decided(queue: BoundedSourceQueue[Update], decision: Decision, nanos: Long): Unit = {
    queue.offer(Published(Decisions, nanos, DecisionJson.of(decision, nanos).getBytes(StandardCharsets.UTF_8)))
    ()
  }

  /** The schema data of every protobuf channel: the recording's descriptor set, base64 as the protocol wants it. */
  private lazy val schemaBase64: String = Base64.getEncoder.encodeToString(RecordingSchema.descriptorSet)

  private[web] def serverInfo: String = JsObject(
    "op" -> JsString("serverInfo"),
    "name" -> JsString("naogateway"),
    "capabilities" -> JsArray(),
    "supportedEncodings" -> JsArray(),
    "metadata" -> JsObject(),
    "sessionId" -> JsString(System.currentTimeMillis().toString)
  ).compactPrint

  private[web] def advertise(channels: Vector[Channel]): String = JsObject(
    "op" -> JsString("advertise"),
    "channels" -> JsArray(channels.map { c =>
      val common =
        Map[String, JsValue]("id" -> JsNumber(c.id), "topic" -> JsString(c.topic), "encoding" -> JsString(c.encoding),
          "schemaName" -> JsString(c.schemaName))
      // A JSON channel without a schema: an empty schema, which viewers take as schemaless JSON.
      if (c.encoding == "protobuf")
        JsObject(common ++ Map("schema" -> JsString(schemaBase64), "schemaEncoding" -> JsString("protobuf")))
      else JsObject(common + ("schema" -> JsString("")))
    })
  ).compactPrint

  private[web] def status(level: Int, message: String): String =
    JsObject("op" -> JsString("status"), "level" -> JsNumber(level), "message" -> JsString(message)).compactPrint

  /** A message-data frame: opcode 1, subscription id (u32), receive time (u64 ns), the payload; little-endian. */
  private[web] def messageData(subscription: Int, nanos: Long, bytes: Array[Byte]): ByteString = {
    val b = ByteBuffer.allocate(13 + bytes.length).order(ByteOrder.LITTLE_ENDIAN)
    b.put(1.toByte).putInt(subscription).putLong(nanos).put(bytes)
    ByteString.fromArrayUnsafe(b.array())
  }

  /** What a client may ask: subscribe, unsubscribe; anything else is bad input. */
  private[web] sealed trait Request
  private[web] final case class Subscribe(subscriptions: Vector[(Int, Int)]) extends Request
  private[web] final case class Unsubscribe(ids: Vector[Int]) extends Request
  private[web] final case class Bad(reason: String) extends Request

  /** A client's text message as a request (total: whatever it holds, it is a request or `Bad`). */
  private[web] def request(text: String): Request =
    Try(text.parseJson.asJsObject).toOption.fold[Request](Bad("not a JSON object")) { o =>
      def ints(v: JsValue): Option[Int] = v match {
        case JsNumber(n) if n.isValidInt => Some(n.toInt)
        case _                           => None
      }
      o.fields.get("op") match {
        case Some(JsString("subscribe")) =>
          o.fields.get("subscriptions") match {
            case Some(JsArray(subs)) =>
              val parsed = subs.map(s =>
                Try(s.asJsObject.fields).toOption.flatMap(f =>
                  for {
                    id <- f.get("id").flatMap(ints); ch <- f.get("channelId").flatMap(ints)
                  } yield (id, ch)))
              if (parsed.forall(_.isDefined)) Subscribe(parsed.flatten)
              else Bad("a subscription needs an id and a channelId")
            case _ => Bad("subscribe needs subscriptions")
          }
        case Some(JsString("unsubscribe")) =>
          o.fields.get("subscriptionIds") match {
            case Some(JsArray(ids)) if ids.forall(ints(_).isDefined) => Unsubscribe(ids.flatMap(ints))
            case _                                                   => Bad("unsubscribe needs subscriptionIds")
          }
        case Some(JsString(op)) => Bad(s"operation '${op.take(40)}' is not supported")
        case _                  => Bad("no op")
      }
    }

  /** Client messages longer than this close the connection (a subscription to every channel is far shorter). */
  private[web] val MaxRequestChars: Int = 64 * 1024

  /** Status replies to bad requests per connection; beyond it they are only counted. */
  private val MaxStatusReplies = 16

  private sealed trait In
  private final case class FromClient(request: Request) extends In
  private final case class FromHub(update: Update) extends In

  /** One client's connection: server info and the channels, then the data of the channels it subscribed to. */
  private[web] def connection(feed: Feed, clientBuffer: Int, badInput: () => Unit)(
      implicit mat: Materializer): Flow[Message, Message, NotUsed] = {
    val requests = Flow[Message].mapAsync(1) {
      case t: TextMessage =>
        t.textStream.limitWeighted(MaxRequestChars.toLong)(_.length.toLong).runFold(new StringBuilder)(_ append _).map(
          b => request(b.toString))(mat.executionContext)
      case b: BinaryMessage =>
        b.dataStream.runWith(Sink.ignore).map(_ => Bad("this server takes no binary messages"))(mat.executionContext)
    }.map(FromClient(_): In)
    val updates = feed.updates.buffer(clientBuffer * 16, OverflowStrategy.fail).map(FromHub(_): In)
    requests.merge(updates, eagerComplete = true)
      .statefulMapConcat { () =>
        var channels = feed.channels.map(c => c.id -> c).toMap
        var subscriptions = Map.empty[Int, Int] // subscription id -> channel id
        var byChannel = Map.empty[Int, Int] // channel id -> subscription id
        var statusReplies = 0
        def bad(reason: String): List[Message] = {
          badInput()
          statusReplies += 1
          if (statusReplies <= MaxStatusReplies) List(TextMessage(status(2, reason))) else Nil
        }
        {
          case FromHub(Advertised(more)) =>
            val fresh = more.filterNot(c => channels.contains(c.id))
            channels ++= fresh.map(c => c.id -> c)
            if (fresh.isEmpty) Nil else List(TextMessage(advertise(fresh)))
          case FromHub(Published(channel, _, _)) if !channels.contains(channel.id) =>
            // Advertised between this connection's start and its joining the hub: advertised now.
            channels += channel.id -> channel
            List(TextMessage(advertise(Vector(channel))))
          case FromHub(Published(channel, nanos, bytes)) =>
            byChannel.get(channel.id).map(sub => BinaryMessage(messageData(sub, nanos, bytes)): Message).toList
          case FromClient(Subscribe(subs)) =>
            subs.toList.flatMap { case (sub, channel) =>
              if (!channels.contains(channel)) bad(s"channel $channel does not exist")
              else if (subscriptions.contains(sub)) bad(s"subscription $sub is taken")
              else if (byChannel.contains(channel)) bad(s"channel $channel is subscribed already")
              else {
                subscriptions += sub -> channel
                byChannel += channel -> sub
                Nil
              }
            }
          case FromClient(Unsubscribe(ids)) =>
            ids.foreach(id => subscriptions.get(id).foreach { ch => byChannel -= ch; subscriptions -= id })
            Nil
          case FromClient(Bad(reason)) => bad(reason)
        }
      }
      .prepend(Source((TextMessage(serverInfo) :: (if (feed.channels.isEmpty) Nil
                                                   else List(TextMessage(advertise(feed.channels))))): List[Message]))
  }

  /** How long a client may take to be connected to the hub. */
  private[web] val ConnectTimeout: FiniteDuration = 3.seconds
}
