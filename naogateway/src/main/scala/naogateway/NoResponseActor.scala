package naogateway

import scala.concurrent.duration.FiniteDuration

import akka.actor.typed.scaladsl.{Behaviors, StashBuffer, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior, PostStop, PreRestart}

import naogateway.wire.{RpcCall, RpcReply, RpcValue}

/**
 * Ordered fire-and-forget commands that still honour the link's request-reply lockstep: one command in flight,
 * the rest stashed (bounded) until its answer arrives, so the robot's 1400-byte module buffer is never flooded.
 */
object NoResponseActor {

  /** What the no-response actor accepts. */
  sealed trait Command

  /** Sends `call` in order; `replyTo`, when given, learns how it ended (the robot's answer, an error or a drop). */
  final case class Send(call: RpcCall, replyTo: Option[ActorRef[CallResult]] = None, priority: Priority = Priority.Command)
      extends Command

  /** A reply with one of this actor's call ids arrived. */
  final case class ReplyReceived(reply: RpcReply) extends Command

  /** The robot's reachability changed. */
  final case class Reachability(online: Boolean) extends Command

  private final case class AnswerTimedOut(callId: Long) extends Command
  private final case class SendOutcome(outcome: Outbox.Outcome) extends Command

  /** Call ids of this actor carry this tag in their two top bits. */
  val CallIdTag: Long = 1L << 30

  /** Commands that set a target (velocity, angles): a newer one replaces its stashed predecessor. */
  val LatestWins: Set[String] = Set("motion.walk", "motion.head", "motion.arms")

  private case object AnswerKey

  /** A no-response actor for robot `robotId`, sending through `robot`. */
  def apply(robotId: Int, settings: CallSettings, robot: ActorRef[RobotActor.FromChild], online: Boolean): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        Behaviors.withStash(settings.stashCapacity) { stash =>
          val outcomes = context.messageAdapter[Outbox.Outcome](SendOutcome.apply)
          robot ! RobotActor.ReachabilityWanted(context.messageAdapter[Boolean](Reachability.apply))
          val actor = new Lockstep(robotId, settings.timeout, robot, outcomes, timers, stash, context.log)
          // Call ids start at a random point per incarnation, so a late reply from before a restart matches nothing new.
          val firstId = java.util.concurrent.ThreadLocalRandom.current().nextLong(0x3fffffffL)
          if (online) actor.communicating(firstId, Map.empty) else actor.offline(firstId)
        }
      }
    }

  private final class Lockstep(
      robotId: Int,
      timeout: FiniteDuration,
      robot: ActorRef[RobotActor.FromChild],
      outcomes: ActorRef[Outbox.Outcome],
      timers: TimerScheduler[Command],
      stash: StashBuffer[Command],
      log: org.slf4j.Logger
  ) {
    private var overflowed = 0L

    private def finish(s: Send, result: Either[CallError, Option[RpcValue]]): Unit =
      s.replyTo.foreach(_ ! CallResult(robotId, s.call.name, result))

    /** Newest replacement of a stashed latest-wins command, by call name. */
    type Newest = Map[String, Send]

    /** Idle: the next command goes out at once. */
    def communicating(lastId: Long, newest: Newest): Behavior[Command] = Behaviors
      .receiveMessage[Command] {
        case s0: Send =>
          // A stashed latest-wins command is swapped for its newest replacement when its turn comes.
          val s = newest.getOrElse(s0.call.name, s0)
          val id = CallIdTag | ((lastId + 1) & 0x3fffffffL)
          // The answer's timer runs before anyone can react to the command going out.
          timers.startSingleTimer(AnswerKey, AnswerTimedOut(id), timeout)
          robot ! RobotActor.Transmit(RobotActor.Outbound.CallOut(s.call.copy(callId = Some(id))), s.priority, Some(outcomes), id)
          waiting(id, s, (lastId + 1) & 0x3fffffffL, newest - s0.call.name)
        case Reachability(false) => toOffline(lastId, newest)
        case Reachability(true) | ReplyReceived(_) | AnswerTimedOut(_) | SendOutcome(_) => Behaviors.same
      }
      .receiveSignal(signals(None, newest))

    /** One command in flight: everything new waits in the stash, in order. */
    private def waiting(id: Long, current: Send, lastId: Long, newest: Newest): Behavior[Command] = Behaviors
      .receiveMessage[Command] {
        case s: Send =>
          val name = s.call.name
          if (LatestWins(name) && (newest.contains(name) || stash.exists {
              case q: Send => q.call.name == name
              case _       => false
            })) {
            newest.get(name).foreach(old => finish(old, Left(CallError.Superseded(robotId, name))))
            if (!newest.contains(name)) stash.foreach {
              case q: Send if q.call.name == name && q != s => finish(q, Left(CallError.Superseded(robotId, name)))
              case _                                         => ()
            }
            waiting(id, current, lastId, newest.updated(name, s))
          } else if (stash.isFull) {
            overflowed += 1
            if (overflowed % 100 == 1)
              log.warn("Robot [{}]: {} command(s) refused so far, {} wait already", robotId, overflowed, stash.size)
            finish(s, Left(CallError.Overloaded(robotId, s"${stash.size} commands wait already")))
            Behaviors.same
          } else {
            stash.stash(s)
            Behaviors.same
          }
        case ReplyReceived(reply) if reply.callId.contains(id) =>
          next(current, reply.result.left.map(CallError.RobotError(robotId, _)), lastId, newest)
        case AnswerTimedOut(timedOut) if timedOut == id =>
          next(current, Left(CallError.Timeout(robotId, current.call.name, timeout)), lastId, newest)
        case SendOutcome(outcome) if outcome.tag == id =>
          CallError.ofOutcome(robotId, outcome).fold(Behaviors.same[Command])(e => next(current, Left(e), lastId, newest))
        case Reachability(false) =>
          timers.cancel(AnswerKey)
          finish(current, Left(CallError.RobotOffline(robotId)))
          toOffline(lastId, newest)
        case Reachability(true) | ReplyReceived(_) | AnswerTimedOut(_) | SendOutcome(_) => Behaviors.same
      }
      .receiveSignal(signals(Some(current), newest))

    /** Ends the command in flight with `result` and sends the next waiting one. */
    private def next(current: Send, result: Either[CallError, Option[RpcValue]], lastId: Long, newest: Newest)
        : Behavior[Command] = {
      timers.cancel(AnswerKey)
      finish(current, result)
      stash.unstash(communicating(lastId, newest), 1, identity)
    }

    private def toOffline(lastId: Long, newest: Newest): Behavior[Command] = {
      failWaiting(newest, CallError.RobotOffline(robotId))
      stash.clear()
      offline(lastId)
    }

    /** Offline: every command fails at once with robot-offline. */
    def offline(lastId: Long): Behavior[Command] = Behaviors.receiveMessage {
      case s: Send =>
        finish(s, Left(CallError.RobotOffline(robotId)))
        robot ! RobotActor.Wanted
        Behaviors.same
      case Reachability(true) => communicating(lastId, Map.empty)
      case Reachability(false) | ReplyReceived(_) | AnswerTimedOut(_) | SendOutcome(_) => Behaviors.same
    }

    private def failWaiting(newest: Newest, error: CallError): Unit = {
      stash.foreach {
        case s: Send => finish(newest.getOrElse(s.call.name, s), Left(error))
        case _       => ()
      }
    }

    private def signals(current: Option[Send], newest: Newest): PartialFunction[(akka.actor.typed.scaladsl.ActorContext[Command], akka.actor.typed.Signal), Behavior[Command]] = {
      case (_, PreRestart) =>
        current.foreach(c => finish(c, Left(CallError.Interrupted(robotId, c.call.name))))
        failWaiting(newest, CallError.Interrupted(robotId, "waiting command"))
        Behaviors.same
      case (_, PostStop) =>
        current.foreach(c => finish(c, Left(CallError.RobotOffline(robotId))))
        failWaiting(newest, CallError.RobotOffline(robotId))
        Behaviors.same
    }
  }
}
