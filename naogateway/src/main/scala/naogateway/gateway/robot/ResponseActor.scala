package naogateway.gateway.robot

import scala.concurrent.duration._

import akka.actor.typed.scaladsl.{Behaviors, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior, PostStop, PreRestart}

import naogateway.wire.{RpcCall, RpcMethod, RpcReply, RpcValue}
import naogateway.access.RobotAccess
import naogateway.api.{CallResult, Priority, RobotFailure}
import naogateway.gateway.CallSettings

/** Request-reply for one robot: correlation ids (from [[CallId]]), per-call deadlines, retries of idempotent calls, and
  * exactly one answer per caller. It sends nothing itself: every attempt is submitted to the robot's one sender
  * (`NoResponseActor`), which orders it among everything else the robot gets.
  *
  * A retry is a new `Request` with a new call id (docs/protocol.md 7.1): a robot answers every request it gets once, so
  * a repeated call id would earn two answers to one request. An answer to any attempt of a call completes it.
  */
object ResponseActor {

  /** What the response actor takes from its robot's actors, and the callers' [[RobotAccess.Call]] wrapped into
    * [[Called]] as it arrives.
    */
  private[naogateway] sealed trait Command

  /** A caller's call. */
  private[naogateway] final case class Called(call: RobotAccess.Call) extends Command

  /** A reply with one of this actor's call ids arrived. */
  private[naogateway] final case class ReplyReceived(reply: RpcReply) extends Command

  /** The robot's reachability changed. */
  private[naogateway] final case class Reachability(online: Boolean) extends Command

  private final case class SendOutcome(outcome: Outbox.Outcome) extends Command
  private final case class OrderNotice(notice: NoResponseActor.Notice) extends Command
  private final case class AttemptTimedOut(key: Long, attempt: Int) extends Command

  /** What the responder keeps with a call: `ids` are the call ids of its attempts, the first one being its key. */
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

  /** The response actor of robot `robotId`, submitting to `sender`; `robot` owns reachability, hears round trips.
    * Spawned as both its protocols: the callers' calls are wrapped into its own as they arrive, in its own mailbox.
    */
  private[naogateway] def apply(robotId: Int, settings: CallSettings, robot: ActorRef[RobotActor.FromChild],
      sender: ActorRef[NoResponseActor.Command], online: Boolean): Behavior[Any] =
    Behaviors.setup[Command] { context =>
      Behaviors.withTimers { timers =>
        val outcomes = context.messageAdapter[Outbox.Outcome](SendOutcome.apply)
        val notices = context.messageAdapter[NoResponseActor.Notice](OrderNotice.apply)
        robot ! RobotActor.ReachabilityWanted(context.messageAdapter[Boolean](Reachability.apply))
        val responder = new Responder(robotId, settings, robot, sender, outcomes, notices, timers)
        responder.running(Map.empty, online, CallId.randomStart())
      }
    }.transformMessages[Any] {
      case call: RobotAccess.Call => Called(call)
      case own: Command           => own
    }

  private final class Responder(
      robotId: Int,
      settings: CallSettings,
      robot: ActorRef[RobotActor.FromChild],
      sender: ActorRef[NoResponseActor.Command],
      outcomes: ActorRef[Outbox.Outcome],
      notices: ActorRef[NoResponseActor.Notice],
      timers: TimerScheduler[Command]
  ) {
    private type Calls = Map[Long, Pending]

    private def answer(p: Pending, result: Either[RobotFailure, Option[RpcValue]]): Unit =
      p.replyTo ! CallResult(robotId, p.call.name, result)

    private def nextId(lastId: Long): Long = CallId.next(CallId.Owner.Response, lastId)

    /** Attempt `p.attempts` of call `key` runs from now: its timer starts before anyone can react to it going out. */
    private def arm(key: Long, p: Pending): Pending = {
      timers.startSingleTimer(key, AttemptTimedOut(key, p.attempts), p.attemptTimeout)
      p.copy(sentAt = System.nanoTime())
    }

    private def attempt(p: Pending, id: Long): RobotFrames.Outbound =
      RobotFrames.Outbound.CallOut(p.call.copy(callId = Some(id)))

    /** Answers call `key`, and frees its room in the robot's buffer. */
    private def settle(calls: Calls, key: Long, result: Either[RobotFailure, Option[RpcValue]]): Calls =
      calls.get(key).fold(calls) { p =>
        timers.cancel(key)
        answer(p, result)
        sender ! NoResponseActor.Finished(key)
        calls - key
      }

    private def failAll(calls: Calls, error: String => RobotFailure): Unit = {
      calls.foreach { case (key, p) =>
        timers.cancel(key)
        answer(p, Left(error(p.call.name)))
      }
      // All at once: a waiting call answered here must not take the room another one frees.
      if (calls.nonEmpty) sender ! NoResponseActor.Finished(calls.keySet)
    }

    private def keyOf(calls: Calls, id: Long): Option[Long] = calls.collectFirst { case (k, p) if p.ids(id) => k }

    def running(calls: Calls, online: Boolean, lastId: Long): Behavior[Command] =
      Behaviors
        .receiveMessage[Command] {
          case Called(c) if !online =>
            c.replyTo ! CallResult(robotId, c.call.name, Left(RobotFailure.RobotOffline(robotId)))
            robot ! RobotActor.Wanted
            Behaviors.same
          case Called(RobotAccess.Call(call, replyTo, priority, timeout, idempotent)) =>
            val id = nextId(lastId)
            val total = timeout.getOrElse(settings.timeout)
            val retries = if (idempotent.getOrElse(RpcMethod.idempotent(call))) settings.idempotentRetries else 0
            val each = total / (retries + 1).toLong
            val p = arm(id, Pending(call, Set(id), replyTo, priority, 1, retries + 1, each, total, 0L))
            val awaits = NoResponseActor.Awaits.Reply(None)
            sender ! NoResponseActor.Submit(attempt(p, id), priority, Some(id), awaits, Some(outcomes), Some(notices))
            running(calls.updated(id, p), online, CallId.count(id))
          case ReplyReceived(reply) =>
            reply.callId.flatMap(keyOf(calls, _)) match {
              case None => Behaviors.same // a late or duplicate reply, or one of a superseded call: answered already
              case Some(key) =>
                val p = calls(key)
                // Karn's rule: only a call sent once gives a clean round-trip sample.
                if (p.attempts == 1) robot ! RobotActor.RoundTrip(System.nanoTime() - p.sentAt)
                running(settle(calls, key, reply.result.left.map(RobotFailure.RobotError(robotId, _))), online, lastId)
            }
          case AttemptTimedOut(key, n) =>
            calls.get(key) match {
              case Some(p) if p.attempts == n && p.attempts < p.maxAttempts =>
                // Sent again as a new request: the same call id twice would be answered twice (protocol.md 7.1).
                val id = nextId(lastId)
                val again = arm(key, p.copy(ids = p.ids + id, attempts = p.attempts + 1))
                robot ! RobotActor.Retransmitted
                sender ! NoResponseActor.Resend(key, attempt(again, id), id)
                running(calls.updated(key, again), online, CallId.count(id))
              case Some(p) if p.attempts == n =>
                val timeout = RobotFailure.Timeout(robotId, p.call.name, p.total.toMillis)
                running(settle(calls, key, Left(timeout)), online, lastId)
              case _ => Behaviors.same
            }
          case SendOutcome(outcome) =>
            (OutcomeFailure.of(robotId, outcome), keyOf(calls, outcome.tag)) match {
              case (Some(error), Some(key)) => running(settle(calls, key, Left(error)), online, lastId)
              case _                        => Behaviors.same
            }
          case OrderNotice(notice) =>
            calls.get(notice.key) match {
              case None    => Behaviors.same
              case Some(p) =>
                // The sender has let go of the call already (all but Queued and SentLate): nothing to tell it.
                def drop(error: RobotFailure): Behavior[Command] = {
                  timers.cancel(notice.key)
                  answer(p, Left(error))
                  running(calls - notice.key, online, lastId)
                }
                notice match {
                  case NoResponseActor.Notice.Queued(key) =>
                    // Its deadline runs from when it leaves (SentLate), as if it had waited in this actor.
                    timers.cancel(key)
                    Behaviors.same
                  case NoResponseActor.Notice.SentLate(key) => running(calls.updated(key, arm(key, p)), online, lastId)
                  case NoResponseActor.Notice.Superseded(_) => drop(RobotFailure.Superseded(robotId, p.call.name))
                  case NoResponseActor.Notice.Refused(_, reason) => drop(RobotFailure.Overloaded(robotId, reason))
                  case NoResponseActor.Notice.Interrupted(_)     => drop(RobotFailure.Interrupted(robotId, p.call.name))
                }
            }
          case Reachability(nowOnline) =>
            if (!nowOnline) {
              failAll(calls, _ => RobotFailure.RobotOffline(robotId))
              running(Map.empty, online = false, lastId)
            } else running(calls, online = true, lastId)
        }
        .receiveSignal {
          case (_, PreRestart) =>
            failAll(calls, RobotFailure.Interrupted(robotId, _))
            Behaviors.same
          case (_, PostStop) =>
            failAll(calls, _ => RobotFailure.RobotOffline(robotId))
            Behaviors.same
        }
  }
}
