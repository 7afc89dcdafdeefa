package naogateway

import akka.actor.typed.scaladsl.{Behaviors, StashBuffer}
import akka.actor.typed.{ActorRef, Behavior, PostStop, PreRestart}

import naogateway.wire.{ActuatorGroup, RpcCall, RpcMethod, RpcValue}

/**
 * Ordered fire-and-forget commands: a lockstep client of its sibling `ResponseActor`, which alone sends to the robot.
 * One command in flight (sent once, no retries), the rest stashed (bounded) until its answer arrives; a newer command
 * of a slot takes the place of a stashed one of that slot (latest wins).
 */
object NoResponseActor {

  /** What the no-response actor accepts. */
  sealed trait Command

  /** Sends `call` in order; `replyTo`, when given, learns how it ended (the robot's answer, an error or a drop). */
  final case class Send(call: RpcCall, replyTo: Option[ActorRef[CallResult]] = None, priority: Priority = Priority.Command)
      extends Command

  private final case class Answered(result: CallResult) extends Command

  /** A no-response actor for robot `robotId`, calling through `response`. */
  def apply(robotId: Int, settings: CallSettings, response: ActorRef[ResponseActor.Command]): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withStash(settings.stashCapacity) { stash =>
        new Lockstep(robotId, response, context.messageAdapter(Answered.apply), stash, context.log).idle(Map.empty)
      }
    }

  private final class Lockstep(
      robotId: Int,
      response: ActorRef[ResponseActor.Command],
      answers: ActorRef[CallResult],
      stash: StashBuffer[Command],
      log: org.slf4j.Logger
  ) {
    private var overflowed = 0L

    private def finish(s: Send, result: Either[RobotFailure, Option[RpcValue]]): Unit =
      s.replyTo.foreach(_ ! CallResult(robotId, s.call.name, result))

    /** The newest replacement of a stashed command, by slot. */
    type Newest = Map[ActuatorGroup, Send]

    /** Idle: the next command goes to the response actor at once. */
    def idle(newest: Newest): Behavior[Command] = Behaviors
      .receiveMessage[Command] {
        case s0: Send =>
          // A stashed command of a slot is swapped for its newest replacement when its turn comes.
          val slot = RpcMethod.slotOf(s0.call)
          val s = slot.flatMap(newest.get).getOrElse(s0)
          response ! ResponseActor.Call(s.call, answers, s.priority, idempotent = Some(false))
          waiting(s, slot.fold(newest)(newest - _))
        case Answered(_) => Behaviors.same
      }
      .receiveSignal(signals(None, newest))

    /** One command in flight: everything new waits in the stash, in order. */
    private def waiting(current: Send, newest: Newest): Behavior[Command] = Behaviors
      .receiveMessage[Command] {
        case s: Send =>
          val slot = RpcMethod.slotOf(s.call)
          val stashedOfSlot = slot.exists(sl => newest.contains(sl) || stash.exists {
            case q: Send => RpcMethod.slotOf(q.call).contains(sl)
            case _       => false
          })
          if (stashedOfSlot) {
            val sl = slot.get
            newest.get(sl) match {
              case Some(old) => finish(old, Left(RobotFailure.Superseded(robotId, old.call.name)))
              case None =>
                stash.foreach {
                  case q: Send if RpcMethod.slotOf(q.call).contains(sl) => finish(q, Left(RobotFailure.Superseded(robotId, q.call.name)))
                  case _                                                => ()
                }
            }
            waiting(current, newest.updated(sl, s))
          } else if (stash.isFull) {
            overflowed += 1
            if (overflowed % 100 == 1)
              log.warn("Robot [{}]: {} command(s) refused so far, {} wait already", robotId, overflowed, stash.size)
            finish(s, Left(RobotFailure.Overloaded(robotId, s"${stash.size} commands wait already")))
            Behaviors.same
          } else {
            stash.stash(s)
            Behaviors.same
          }
        case Answered(result) =>
          // The response actor answers every call exactly once, also when it restarts or stops.
          finish(current, result.result)
          stash.unstash(idle(newest), 1, identity)
      }
      .receiveSignal(signals(Some(current), newest))

    private def failWaiting(newest: Newest, error: RobotFailure): Unit =
      stash.foreach {
        case s: Send => finish(RpcMethod.slotOf(s.call).flatMap(newest.get).getOrElse(s), Left(error))
        case _       => ()
      }

    private def signals(current: Option[Send], newest: Newest)
        : PartialFunction[(akka.actor.typed.scaladsl.ActorContext[Command], akka.actor.typed.Signal), Behavior[Command]] = {
      case (_, PreRestart) =>
        current.foreach(c => finish(c, Left(RobotFailure.Interrupted(robotId, c.call.name))))
        failWaiting(newest, RobotFailure.Interrupted(robotId, "waiting command"))
        Behaviors.same
      case (_, PostStop) =>
        current.foreach(c => finish(c, Left(RobotFailure.RobotOffline(robotId))))
        failWaiting(newest, RobotFailure.RobotOffline(robotId))
        Behaviors.same
    }
  }
}
