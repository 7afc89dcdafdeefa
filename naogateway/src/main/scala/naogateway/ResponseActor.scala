package naogateway

import scala.concurrent.duration._

import akka.actor.typed.scaladsl.{Behaviors, StashBuffer, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior, PostStop, PreRestart}

import naogateway.wire.{RpcCall, RpcReply, RpcValue}

/**
 * Request-reply with one robot: correlation ids, per-call timeouts, retries of idempotent calls, one answer per call.
 *
 * A retry is a new `Request` with a new call id (docs/protocol.md 7.1): a robot answers every request it gets once,
 * so a repeated call id would earn two answers to one request. An answer to any attempt of a call completes it.
 */
object ResponseActor {

  /** What the response actor accepts. */
  sealed trait Command

  /** Calls the robot; `replyTo` gets exactly one `CallResult`. `timeout` overrides the configured one. */
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

  private final case class SendOutcome(outcome: Outbox.Outcome) extends Command
  private final case class AttemptTimedOut(key: Long, attempt: Int) extends Command

  /** Call ids of this actor carry this tag in their two top bits. */
  val CallIdTag: Long = 0L

  /** Calls that may be sent again when no reply came: reads, and commands that set an absolute target. */
  val IdempotentCalls: Set[String] =
    Set("system.battery", "system.ping", "motion.getPosture", "motion.head", "motion.arms", "motion.stop", "motion.walk")

  /** Calls in flight at once; more wait in the stash so the robot's 1400-byte module buffer is not flooded. */
  val MaxInFlight: Int = 4

  /** One call in flight; `ids` are the call ids of its attempts, the first one being its key. */
  private final case class Pending(
      call: RpcCall,
      ids: Set[Long],
      replyTo: ActorRef[CallResult],
      attempts: Int,
      maxAttempts: Int,
      attemptTimeout: FiniteDuration,
      total: FiniteDuration,
      sentAt: Long
  )

  /** A response actor for robot `robotId`, sending through `robot`. */
  def apply(robotId: Int, settings: CallSettings, robot: ActorRef[RobotActor.FromChild], online: Boolean): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        Behaviors.withStash(settings.stashCapacity) { stash =>
          val outcomes = context.messageAdapter[Outbox.Outcome](SendOutcome.apply)
          robot ! RobotActor.ReachabilityWanted(context.messageAdapter[Boolean](Reachability.apply))
          new Responder(robotId, settings, robot, outcomes, timers, stash)
            .running(Map.empty, online, java.util.concurrent.ThreadLocalRandom.current().nextLong(0x3fffffffL))
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

    private def answer(p: Pending, result: Either[CallError, Option[RpcValue]]): Unit =
      p.replyTo ! CallResult(robotId, p.call.name, result)

    // The attempt's timer (keyed by the call's first id) runs before anyone can react to the attempt going out.
    private def transmit(key: Long, id: Long, p: Pending, priority: Priority): Unit = {
      timers.startSingleTimer(key, AttemptTimedOut(key, p.attempts), p.attemptTimeout)
      robot ! RobotActor.Transmit(RobotActor.Outbound.CallOut(p.call.copy(callId = Some(id))), priority, Some(outcomes), id)
    }

    private def nextId(lastId: Long): Long = CallIdTag | ((lastId + 1) & 0x3fffffffL)

    /** The call one of whose attempts carried `id`, with its key; at most MaxInFlight calls are searched. */
    private def attemptOf(pending: Map[Long, Pending], id: Long): Option[(Long, Pending)] =
      pending.find { case (_, p) => p.ids(id) }

    private def failAll(pending: Map[Long, Pending], error: CallError): Unit =
      pending.foreach { case (id, p) =>
        timers.cancel(id)
        answer(p, Left(error))
      }

    /** Answers call `id`, forgets it, and lets the next waiting call in. */
    private def settle(pending: Map[Long, Pending], id: Long, p: Pending, result: Either[CallError, Option[RpcValue]],
        online: Boolean, lastId: Long): Behavior[Command] = {
      timers.cancel(id)
      answer(p, result)
      stash.unstash(running(pending - id, online, lastId), 1, identity)
    }

    def running(pending: Map[Long, Pending], online: Boolean, lastId: Long): Behavior[Command] =
      Behaviors
        .receiveMessage[Command] {
          case c: Call if !online =>
            c.replyTo ! CallResult(robotId, c.call.name, Left(CallError.RobotOffline(robotId)))
            robot ! RobotActor.Wanted
            Behaviors.same
          case c: Call if pending.size >= MaxInFlight =>
            if (stash.isFull)
              c.replyTo ! CallResult(robotId, c.call.name,
                Left(CallError.Overloaded(robotId, s"${pending.size} calls in flight and ${stash.size} waiting")))
            else stash.stash(c)
            Behaviors.same
          case Call(call, replyTo, priority, timeout, idempotent) =>
            val id = nextId(lastId)
            val total = timeout.getOrElse(settings.timeout)
            val retries = if (idempotent.getOrElse(IdempotentCalls(call.name))) settings.idempotentRetries else 0
            val p = Pending(call, Set(id), replyTo, 1, retries + 1, total / (retries + 1).toLong, total, System.nanoTime())
            transmit(id, id, p, priority)
            running(pending.updated(id, p), online, id & 0x3fffffffL)
          case ReplyReceived(reply) =>
            reply.callId.flatMap(attemptOf(pending, _)) match {
              case None => Behaviors.same // a late or duplicate reply: the call was answered already
              case Some((key, p)) =>
                // Karn's rule: only a call sent once gives a clean round-trip sample.
                if (p.attempts == 1) robot ! RobotActor.RoundTrip(System.nanoTime() - p.sentAt)
                settle(pending, key, p, reply.result.left.map(CallError.RobotError(robotId, _)), online, lastId)
            }
          case AttemptTimedOut(key, attempt) =>
            pending.get(key) match {
              case Some(p) if p.attempts == attempt && p.attempts < p.maxAttempts =>
                // Sent again as a new request: the same call id twice would be answered twice (protocol.md 7.1).
                val id = nextId(lastId)
                val again = p.copy(ids = p.ids + id, attempts = p.attempts + 1)
                robot ! RobotActor.Retransmitted
                transmit(key, id, again, Priority.Command)
                running(pending.updated(key, again), online, id & 0x3fffffffL)
              case Some(p) if p.attempts == attempt =>
                settle(pending, key, p, Left(CallError.Timeout(robotId, p.call.name, p.total)), online, lastId)
              case _ => Behaviors.same
            }
          case SendOutcome(outcome) =>
            (CallError.ofOutcome(robotId, outcome), attemptOf(pending, outcome.tag)) match {
              case (Some(error), Some((key, p))) => settle(pending, key, p, Left(error), online, lastId)
              case _                             => Behaviors.same
            }
          case Reachability(nowOnline) =>
            if (!nowOnline) {
              failAll(pending, CallError.RobotOffline(robotId))
              // Waiting calls fail fast too: they meet the offline state when unstashed.
              stash.unstashAll(running(Map.empty, online = false, lastId))
            } else running(pending, online = true, lastId)
        }
        .receiveSignal {
          case (_, PreRestart) =>
            failAll(pending, CallError.Interrupted(robotId, "pending call"))
            stash.foreach {
              case c: Call => c.replyTo ! CallResult(robotId, c.call.name, Left(CallError.Interrupted(robotId, c.call.name)))
              case _       => ()
            }
            Behaviors.same
          case (_, PostStop) =>
            failAll(pending, CallError.RobotOffline(robotId))
            stash.foreach {
              case c: Call => c.replyTo ! CallResult(robotId, c.call.name, Left(CallError.RobotOffline(robotId)))
              case _       => ()
            }
            Behaviors.same
        }
  }
}
