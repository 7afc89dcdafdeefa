package naogateway.gateway.link

import scala.concurrent.Future
import scala.jdk.DurationConverters._

import akka.Done
import akka.actor.CoordinatedShutdown
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.scaladsl.adapter._
import akka.actor.typed.{
  ActorRef,
  ActorSystem,
  Behavior,
  DispatcherSelector,
  Extension,
  ExtensionId,
  PostStop,
  PreRestart
}
import org.zeromq.{SocketType, ZMQ, ZMsg}

import naogateway.proto.{RobotHealth, Status}
import naogateway.wire.{MessageContents, RpcCall, RpcReply, RpcValue}
import naogateway.api.Priority
import naogateway.gateway.ZeroMqLinkSettings
import naogateway.gateway.robot.RobotFrames.Outbound
import naogateway.gateway.robot.{CallId, NoResponseActor, Outbox}
import naogateway.transport.ZeroMqLoop

/** The link to a robot that serves the RPC over a ZeroMQ REP socket: requests go out on a DEALER socket (so several may
  * wait in the robot's queue, answered in order), replies come back as decoded messages. Such a robot cannot push
  * keep-alives, so the link polls its status and hands each complete answer on as the robot's keep-alive. Its polls go
  * out through the robot's sender (whose ref it holds, as the stream does) and the outbox like every other request.
  */
object ZeroMqRobotLink {

  /** What a link accepts. */
  sealed trait Command

  /** Sends one serialized `Message` to the robot; `outcome`, when given, learns whether it went out, marked with `tag`.
    * Only the outbox sends it, behind the competition gate and the team budget (`Outbox.Send.via`).
    */
  private[naogateway] final case class Send(bytes: Array[Byte], outcome: Option[ActorRef[Outbox.Outcome]], tag: Long)
      extends Command

  private final case class Received(bytes: Array[Byte]) extends Command
  private final case class PollSent(outcome: Outbox.Outcome) extends Command
  private case object StatusTick extends Command
  private case object StatusKey

  /** What a link tells its owner. */
  sealed trait Event

  /** A message from the robot (a reply, or the keep-alive built from a status poll), `bytes` long on the wire. */
  final case class MessageReceived(contents: MessageContents, bytes: Int) extends Event

  /** Something arrived that is not a `Message`. */
  final case class MessageRejected(reason: String) extends Event

  /** The calls of one status poll, answered by every robot of the RPC contract (docs/protocol.md 7.2). */
  val StatusCalls: Vector[(String, String)] =
    Vector("system" -> "ping", "system" -> "battery", "motion" -> "getPosture")

  /** A link to robot `robotId` at `endpoint`, reporting to `owner` and polling through the robot's `sender`; the socket
    * lives on `loop`.
    */
  def apply(
      robotId: Int,
      endpoint: String,
      settings: ZeroMqLinkSettings,
      owner: ActorRef[Event],
      sender: ActorRef[NoResponseActor.Command],
      loop: ZeroMqLoop
  ): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        val slot = new SocketSlot
        val self = context.self
        loop.submit { sockets =>
          val socket = sockets.socket(SocketType.DEALER)
          // Queue only to a live connection: requests for a robot that is down fail at once instead of
          // reaching it, stale, when it comes back. jeromq's flag reads the other way round from libzmq's
          // ZMQ_IMMEDIATE: false here means "attach the pipe only once connected".
          socket.setImmediate(false)
          socket.setSndHWM(settings.sendQueue)
          // A jeromq client now and then stalls in the handshake after connecting: drop such a connection soon.
          socket.setHandshakeIvl(settings.handshakeTimeout.toMillis.toInt)
          socket.connect(endpoint)
          sockets.onReadable(socket) { s =>
            val message = ZMsg.recvMsg(s, ZMQ.DONTWAIT)
            if (message == null) false
            else {
              // A REP socket answers [empty delimiter, body]; the body is the last frame.
              if (message.size() >= 1) self ! Received(message.getLast.getData)
              message.destroy()
              true
            }
          }
          slot.socket = socket
        }
        val pollOutcomes = context.messageAdapter[Outbox.Outcome](PollSent.apply)
        timers.startTimerWithFixedDelay(StatusKey, StatusTick, settings.statusInterval)
        context.log.info("Robot [{}]: ZeroMQ link to {}", robotId, endpoint)

        def transmit(bytes: Array[Byte], outcome: Option[ActorRef[Outbox.Outcome]], tag: Long): Unit = {
          val accepted = loop.submit { _ =>
            val socket = slot.socket
            val sent = socket != null && socket.send(Array.emptyByteArray, ZMQ.SNDMORE | ZMQ.DONTWAIT) &&
              socket.send(bytes, ZMQ.DONTWAIT)
            outcome.foreach(
              _ ! (if (sent) Outbox.Accepted(tag) else Outbox.Dropped(tag, "no ZeroMQ connection to the robot")))
          }
          if (!accepted) outcome.foreach(_ ! Outbox.Dropped(tag, "the ZeroMQ link is closing"))
        }

        def running(poll: Option[Poll], lastPollId: Long): Behavior[Command] =
          Behaviors
            .receiveMessage[Command] {
              case Send(bytes, outcome, tag) =>
                transmit(bytes, outcome, tag)
                Behaviors.same
              case PollSent(Outbox.Accepted(_)) => Behaviors.same
              case PollSent(refused)            =>
                /* Not sent (the gate is closed, or no connection), so never answered: give the poll up now and try
                 * again */
                // at the next tick.
                if (poll.exists(_.waiting.contains(refused.tag))) running(None, lastPollId) else Behaviors.same
              case StatusTick =>
                val now = System.nanoTime()
                if (poll.exists(p => now - p.startedAt < settings.statusTimeout.toNanos)) Behaviors.same
                else {
                  // Polls never overlap: a new one starts only when the last was answered or given up.
                  val ids = StatusCalls.indices.map(i => CallId(CallId.Owner.StatusPoll, lastPollId + 1 + i)).toVector
                  val calls = ids.zip(StatusCalls).map { case (id, (module, method)) =>
                    RpcCall(module, method, Vector.empty, Some(id))
                  }
                  // The sender counts them against the robot's in-flight cap; each one's outcome comes back here, so a
                  // refused poll is given up at once.
                  val hold = NoResponseActor.Awaits.Reply(Some(settings.statusTimeout))
                  calls.foreach(c =>
                    sender ! NoResponseActor.Submit(Outbound.CallOut(c), Priority.Heartbeat, c.callId, hold,
                      Some(pollOutcomes)))
                  running(Some(Poll(now, ids.zip(StatusCalls.map(_._2)).toMap, Map.empty, 0)), CallId.count(ids.last))
                }
              case Received(bytes) =>
                MessageContents.parse(bytes) match {
                  case Left(error) =>
                    owner ! MessageRejected(s"bad reply: ${error.describe}")
                    Behaviors.same
                  case Right(contents) =>
                    val pollReply = for {
                      response <- contents.rpcResponse
                      id <- response.callId.map(_ & 0xffffffffL)
                      if CallId.ownerOf(id).contains(CallId.Owner.StatusPoll)
                    } yield RpcReply.fromProto(response) -> id
                    pollReply match {
                      case None =>
                        owner ! MessageReceived(contents, bytes.length)
                        Behaviors.same
                      case Some((reply, id)) =>
                        // It no longer takes room in the robot's buffer.
                        sender ! NoResponseActor.Finished(id)
                        poll.filter(_.waiting.contains(id)) match {
                          case None => Behaviors.same // an answer to a poll given up already
                          case Some(p) =>
                            val next = p.answered(id, reply, bytes.length)
                            if (next.waiting.nonEmpty) running(Some(next), lastPollId)
                            else {
                              owner ! MessageReceived(next.keepAlive(robotId), next.bytes)
                              running(None, lastPollId)
                            }
                        }
                    }
                }
            }
            .receiveSignal {
              case (_, PostStop | PreRestart) =>
                loop.submit(sockets => if (slot.socket != null) sockets.close(slot.socket))
                Behaviors.same
            }

        running(None, 0L)
      }
    }

  /** Holds the socket; written and read only on the loop's thread. */
  private final class SocketSlot {
    var socket: ZMQ.Socket = null
  }

  /** One status poll: the calls still unanswered and the answers so far, by method. */
  private final case class Poll(startedAt: Long, waiting: Map[Long, String], answers: Map[String, RpcValue],
      bytes: Int) {
    def answered(id: Long, reply: RpcReply, size: Int): Poll = {
      val method = waiting(id)
      // An error answer still proves the robot is there; only the value is missing then.
      val value = reply.result.toOption.flatten
      Poll(startedAt, waiting - id, value.fold(answers)(v => answers.updated(method, v)), bytes + size)
    }

    /** The keep-alive the answers make: `Status` and `RobotHealth`, as a CM-530 would send them. */
    def keepAlive(robotId: Int): MessageContents = {
      val uptime = answers.get("ping").collect { case RpcValue.UInt(ms) => ms }
      val battery = answers.get("battery").collect {
        case RpcValue.Number(v) => v
        case RpcValue.UInt(v)   => v.toFloat
      }
      val posture = answers.get("getPosture").collect { case RpcValue.Text(p) => p }
      MessageContents(
        robotId,
        status =
          Some(Status(timestamp = uptime, timeOnline = uptime.map(ms => (ms / 1000L).toInt), currentState = posture)),
        robotHealth = Some(RobotHealth(batteryVoltage = battery, posture = posture, uptimeMs = uptime.map(_.toInt)))
      )
    }
  }

  /** The one socket loop of an actor system's robot links, started on first use and stopped with the system. */
  final class SharedLoop(system: ActorSystem[_]) extends Extension {

    /** The loop; its thread comes from `naogateway.zeromq.dispatcher`. */
    val loop: ZeroMqLoop = {
      val settings = system.settings.config.getConfig("naogateway.zeromq")
      val l = new ZeroMqLoop("zeromq-robots", settings.getDuration("poll-timeout").toScala)
      l.start(system.dispatchers.lookup(DispatcherSelector.fromConfig("naogateway.zeromq.dispatcher")))
      CoordinatedShutdown(system.toClassic).addTask(CoordinatedShutdown.PhaseBeforeActorSystemTerminate,
        "zeromq-robot-links") { () =>
        l.stop()
      }
      system.whenTerminated.foreach(_ => l.stop())(scala.concurrent.ExecutionContext.parasitic)
      l
    }

    /** Stops the loop now (normally left to the actor system's shutdown). */
    def stop(): Future[Done] = loop.stop()
  }

  /** The extension's id. */
  object SharedLoop extends ExtensionId[SharedLoop] {
    def createExtension(system: ActorSystem[_]): SharedLoop = new SharedLoop(system)
  }
}
