package naogateway

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.actor.typed.scaladsl.{Behaviors, StashBuffer, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior, PostStop, PreRestart}

import naogateway.link.ZeroMqRobotLink
import naogateway.wire.{HeaderForm, MessageContents, RpcCall, RpcMethod, RpcReply, RpcValue}

/**
 * The one owner of a robot's outbound command order: every call the robot gets passes here, in the order
 * `CommandOrder` decides (slots, supersession, the in-flight cap), and leaves straight for the outbox.
 *
 * Request-reply: correlation ids, per-call timeouts, retries of idempotent calls, one answer per call. A retry is a
 * new `Request` with a new call id (docs/protocol.md 7.1): a robot answers every request it gets once, so a repeated
 * call id would earn two answers to one request. An answer to any attempt of a call completes it.
 */
object ResponseActor {

  /** What the response actor accepts. */
  sealed trait Command

  /**
   * Calls the robot; `replyTo` gets exactly one `CallResult`. `timeout` overrides the configured one; `idempotent`
   * overrides the method table's word on whether the call may be sent again (`Some(false)`: no retries).
   */
  final case class Call(
      call: RpcCall,
      replyTo: ActorRef[CallResult],
      priority: Priority = Priority.Command,
      timeout: Option[FiniteDuration] = None,
      idempotent: Option[Boolean] = None
  ) extends Command

  /** A reply with one of this actor's call ids arrived. */
  final case class ReplyReceived(reply: RpcReply) extends Command

  /** The robot's reachability changed. */
  final case class Reachability(online: Boolean) extends Command

  /** Where the robot's datagrams go now; the robot actor owns it and pushes every change. */
  final case class RouteChanged(route: Route) extends Command

  private final case class SendOutcome(outcome: Outbox.Outcome) extends Command
  private final case class AttemptTimedOut(key: Long, attempt: Int) extends Command

  /** How a call reaches the robot. */
  sealed trait Route extends Product with Serializable

  /** The two routes, one per transport. */
  object Route {

    /** FU-Remote frames in `form` to `to` through the outbox; `signed`: the outbox signs them (the robot must sign). */
    final case class Datagrams(outbox: ActorRef[Outbox.Command], to: InetSocketAddress, form: HeaderForm, signed: Boolean = false)
        extends Route

    /** Serialized `Message`s through the robot's ZeroMQ link. */
    final case class ZeroMq(link: ActorRef[ZeroMqRobotLink.Command]) extends Route
  }

  /** Calls in flight at once; more wait so the robot's 1400-byte module buffer is not flooded. Safety never waits. */
  // Fixed, not a setting: the bound follows from the one 1400-byte buffer the robot's module has for both directions
  // (protocol.md 1), which no gateway configuration changes; a larger value would let replies overrun it.
  val MaxInFlight: Int = 4

  /** What the owner keeps with a call: `ids` are the call ids of its attempts, the first one being its key. */
  private final case class Pending(
      call: RpcCall,
      ids: Set[Long],
      replyTo: ActorRef[CallResult],
      priority: Priority,
      attempts: Int,
      maxAttempts: Int,
      attemptTimeout: FiniteDuration,
      total: FiniteDuration,
      sentAt: Long
  )

  private type Order = CommandOrder[Pending]

  /** A response actor for robot `robotId`; `robot` owns the route and reachability, and hears round trips. */
  def apply(robotId: Int, settings: CallSettings, robot: ActorRef[RobotActor.FromChild], online: Boolean): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        Behaviors.withStash(settings.stashCapacity) { stash =>
          val outcomes = context.messageAdapter[Outbox.Outcome](SendOutcome.apply)
          robot ! RobotActor.ReachabilityWanted(context.messageAdapter[Boolean](Reachability.apply))
          // The route is the robot actor's: asked for on every (re)start, pushed on every change.
          robot ! RobotActor.RouteWanted(context.self)
          val firstId = CallId.randomStart()
          new Responder(robotId, settings, robot, outcomes, timers, stash).awaitingRoute(online, firstId)
        }
      }
    }

  private final class Responder(
      robotId: Int,
      settings: CallSettings,
      robot: ActorRef[RobotActor.FromChild],
      outcomes: ActorRef[Outbox.Outcome],
      timers: TimerScheduler[Command],
      stash: StashBuffer[Command]
  ) {

    private def answer(p: Pending, result: Either[RobotFailure, Option[RpcValue]]): Unit =
      p.replyTo ! CallResult(robotId, p.call.name, result)

    private def answer(c: Call, error: RobotFailure): Unit = c.replyTo ! CallResult(robotId, c.call.name, Left(error))

    private def nextId(lastId: Long): Long = CallId.next(CallId.Owner.Response, lastId)

    /** Before the robot actor has told the route: calls wait (bounded). */
    def awaitingRoute(online: Boolean, lastId: Long): Behavior[Command] = Behaviors
      .receiveMessage[Command] {
        case RouteChanged(route) =>
          stash.unstashAll(running(CommandOrder.empty(MaxInFlight, settings.stashCapacity), online, lastId, route))
        case Reachability(nowOnline) => awaitingRoute(nowOnline, lastId)
        case c: Call if stash.isFull =>
          answer(c, RobotFailure.Overloaded(robotId, s"${stash.size} calls wait for the robot's address"))
          Behaviors.same
        case other =>
          stash.stash(other)
          Behaviors.same
      }
      .receiveSignal {
        case (_, PreRestart) =>
          failStashed(c => RobotFailure.Interrupted(robotId, c.call.name))
          Behaviors.same
        case (_, PostStop) =>
          failStashed(_ => RobotFailure.RobotOffline(robotId))
          Behaviors.same
      }

    private def failStashed(error: Call => RobotFailure): Unit =
      stash.foreach {
        case c: Call => answer(c, error(c))
        case _       => ()
      }

    /** Sends attempt `id` of call `key`; the attempt's timer runs before anyone can react to it going out. */
    private def transmit(route: Route, key: Long, id: Long, p: Pending): Option[RobotFailure] = {
      timers.startSingleTimer(key, AttemptTimedOut(key, p.attempts), p.attemptTimeout)
      val contents = MessageContents(robotId, rpcRequest = Some(p.call.copy(callId = Some(id)).toProto))
      route match {
        case Route.Datagrams(outbox, to, form, signed) =>
          MessageContents.encodeFrame(contents, form) match {
            case Right(bytes) =>
              robot ! RobotActor.SentDirect(bytes.length)
              outbox ! Outbox.Send(robotId, to, bytes, p.priority, Some(outcomes), id, signed)
              None
            case Left(error) => Some(RobotFailure.Overloaded(robotId, error.describe))
          }
        case Route.ZeroMq(link) =>
          val bytes = contents.toProtobuf
          robot ! RobotActor.SentDirect(bytes.length)
          link ! ZeroMqRobotLink.Send(bytes, Some(outcomes), id)
          None
      }
    }

    /** Carries out the order's steps: supersessions first (their withdrawals reach the outbox before any send). */
    private def perform(order: Order, steps: Vector[CommandOrder.Step[Pending]], route: Route): Order =
      steps.foldLeft(order) {
        case (o, CommandOrder.Superseded(e, wasInFlight)) =>
          if (wasInFlight) {
            timers.cancel(e.key)
            route match {
              case Route.Datagrams(outbox, _, _, _) => outbox ! Outbox.Withdraw(robotId, e.payload.ids)
              case Route.ZeroMq(_)               => () // a ZeroMQ link holds nothing back: there is nothing to withdraw
            }
          }
          answer(e.payload, Left(RobotFailure.Superseded(robotId, e.payload.call.name)))
          o
        case (o, CommandOrder.Refused(e)) =>
          answer(e.payload, Left(RobotFailure.Overloaded(robotId,
            s"${o.inFlight.size} calls in flight and ${o.waiting.size} waiting")))
          o
        case (o, CommandOrder.Transmit(e)) =>
          val sent = e.payload.copy(sentAt = System.nanoTime())
          transmit(route, e.key, e.key, sent) match {
            case None => o.updated(e.key, sent)
            case Some(error) =>
              timers.cancel(e.key)
              answer(sent, Left(error))
              val (next, more) = o.complete(e.key)
              perform(next, more, route)
          }
      }

    private def failAll(order: Order, error: String => RobotFailure): Unit = {
      val (_, flying, waiting) = order.drained
      (flying ++ waiting).foreach { e =>
        timers.cancel(e.key)
        answer(e.payload, Left(error(e.payload.call.name)))
      }
    }

    /** Answers call `key` and lets waiting calls in. */
    private def settle(order: Order, key: Long, p: Pending, result: Either[RobotFailure, Option[RpcValue]], online: Boolean,
        lastId: Long, route: Route): Behavior[Command] = {
      timers.cancel(key)
      answer(p, result)
      val (next, steps) = order.complete(key)
      running(perform(next, steps, route), online, lastId, route)
    }

    def running(order: Order, online: Boolean, lastId: Long, route: Route): Behavior[Command] =
      Behaviors
        .receiveMessage[Command] {
          case c: Call if !online =>
            answer(c, RobotFailure.RobotOffline(robotId))
            robot ! RobotActor.Wanted
            Behaviors.same
          case Call(call, replyTo, priority, timeout, idempotent) =>
            val id = nextId(lastId)
            val total = timeout.getOrElse(settings.timeout)
            val retries = if (idempotent.getOrElse(RpcMethod.idempotent(call))) settings.idempotentRetries else 0
            val p = Pending(call, Set(id), replyTo, priority, 1, retries + 1, total / (retries + 1).toLong, total, 0L)
            val (next, steps) = order.submit(CommandOrder.Entry(id, RpcMethod.slotOf(call), priority == Priority.Safety, p,
              replaceable = RpcMethod.of(call).forall(_.latestWins)))
            running(perform(next, steps, route), online, CallId.count(id), route)
          case ReplyReceived(reply) =>
            reply.callId.flatMap(id => order.findInFlight(_.ids(id))) match {
              case None => Behaviors.same // a late or duplicate reply, or one of a superseded call: answered already
              case Some(e) =>
                // Karn's rule: only a call sent once gives a clean round-trip sample.
                if (e.payload.attempts == 1) robot ! RobotActor.RoundTrip(System.nanoTime() - e.payload.sentAt)
                settle(order, e.key, e.payload, reply.result.left.map(RobotFailure.RobotError(robotId, _)), online, lastId, route)
            }
          case AttemptTimedOut(key, attempt) =>
            order.inFlightCall(key).map(_.payload) match {
              case Some(p) if p.attempts == attempt && p.attempts < p.maxAttempts =>
                // Sent again as a new request: the same call id twice would be answered twice (protocol.md 7.1).
                val id = nextId(lastId)
                val again = p.copy(ids = p.ids + id, attempts = p.attempts + 1)
                robot ! RobotActor.Retransmitted
                transmit(route, key, id, again) match {
                  case None        => running(order.updated(key, again), online, CallId.count(id), route)
                  case Some(error) => settle(order, key, again, Left(error), online, CallId.count(id), route)
                }
              case Some(p) if p.attempts == attempt =>
                settle(order, key, p, Left(RobotFailure.Timeout(robotId, p.call.name, (p.total).toMillis)), online, lastId, route)
              case _ => Behaviors.same
            }
          case SendOutcome(outcome) =>
            (OutcomeFailure.of(robotId, outcome), order.findInFlight(_.ids(outcome.tag))) match {
              case (Some(error), Some(e)) => settle(order, e.key, e.payload, Left(error), online, lastId, route)
              case _                      => Behaviors.same
            }
          case RouteChanged(newRoute) => running(order, online, lastId, newRoute)
          case Reachability(nowOnline) =>
            if (!nowOnline) {
              failAll(order, _ => RobotFailure.RobotOffline(robotId))
              running(order.drained._1, online = false, lastId, route)
            } else running(order, online = true, lastId, route)
        }
        .receiveSignal {
          case (_, PreRestart) =>
            failAll(order, RobotFailure.Interrupted(robotId, _))
            Behaviors.same
          case (_, PostStop) =>
            failAll(order, _ => RobotFailure.RobotOffline(robotId))
            Behaviors.same
        }
  }
}
