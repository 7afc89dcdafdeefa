package naogateway.gateway.robot

import scala.concurrent.duration.FiniteDuration

import akka.actor.typed.scaladsl.{ActorContext, Behaviors, StashBuffer, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior, PostStop, PreRestart, Signal}

import naogateway.gateway.robot.RobotFrames.{Outbound, Route}
import naogateway.wire.RpcMethod
import naogateway.api.Priority
import naogateway.gateway.CallSettings

/** The one actor that sends to its robot. Everything for robot N passes here: the callers' calls (submitted by
  * `ResponseActor`, which correlates their answers), the heartbeat's probes, option commands, secure-stream segments
  * and a ZeroMQ robot's status polls. They leave in the order `CommandOrder` decides (safety first, latest wins within
  * a slot, never a walk after a stop), at most `MaxInFlight` of them taking room in the robot's buffer at once (the
  * rest wait, bounded), encoded by `RobotFrames`, through the outbox: the one competition gate and the team budget.
  */
object NoResponseActor {

  /** What the sender accepts. */
  sealed trait Command

  /** Sends `out` in order. `key` names it while it takes room (a call's first call id; the sender picks one when
    * `None`); `awaits` says whether it takes room until answered; `outcome` learns the outbox's word on each
    * transmission (marked with its call id, or the key); `notices` learns what the order did with it.
    */
  private[naogateway] final case class Submit(
      out: Outbound,
      priority: Priority,
      key: Option[Long],
      awaits: Awaits,
      outcome: Option[ActorRef[Outbox.Outcome]] = None,
      notices: Option[ActorRef[Notice]] = None
  ) extends Command

  /** Sends the call `key` (in flight) again as `out`, a new request marked `tag` (its new call id). */
  private[naogateway] final case class Resend(key: Long, out: Outbound, tag: Long) extends Command

  /** `keys` were answered or given up: none of them takes room in the robot's buffer or is to leave any more. Only the
    * submitter of each says so (it alone knows when its request has ended); keys given together leave together, before
    * a waiting one takes the room they free.
    */
  private[naogateway] final case class Finished(keys: Set[Long]) extends Command

  /** One request ended. */
  private[naogateway] object Finished {
    def apply(key: Long): Finished = Finished(Set(key))
  }

  /** Where the robot is reached now. */
  private[naogateway] final case class RouteChanged(route: Route) extends Command

  private final case class HoldOver(key: Long) extends Command

  /** Whether something takes room in the robot's buffer until it is answered. */
  private[naogateway] sealed trait Awaits extends Product with Serializable

  /** The two kinds. */
  private[naogateway] object Awaits {

    /** Leaves the buffer as it goes (an option switch, a stream segment): its room frees once it is sent. */
    case object Nothing extends Awaits

    /** Takes room until `Finished`, or until `hold` has passed since it left (when the submitter may never say). */
    final case class Reply(hold: Option[FiniteDuration]) extends Awaits
  }

  /** What the order did with a submitted call. */
  private[naogateway] sealed trait Notice extends Product with Serializable {
    def key: Long
  }

  /** The notices. */
  private[naogateway] object Notice {

    /** A newer call of its slot took its place: it is gone (and withdrawn from the outbox when it was in flight). */
    final case class Superseded(key: Long) extends Notice

    /** The waiting line was full: it never went. */
    final case class Refused(key: Long, reason: String) extends Notice

    /** No room in the robot's buffer: it waits, and its deadline has not started. */
    final case class Queued(key: Long) extends Notice

    /** It waited for room and has left only now: its deadline starts now. */
    final case class SentLate(key: Long) extends Notice

    /** The sender restarted or stopped with it in its order: its fate is unknown. */
    final case class Interrupted(key: Long) extends Notice
  }

  /** Requests in the robot's buffer at once; more wait, so its 1400-byte module buffer is not flooded. */
  // Fixed, not a setting: the bound follows from the one 1400-byte buffer the robot's module has for both directions
  // (protocol.md 1), which no gateway configuration changes; a larger value would let replies overrun it.
  val MaxInFlight: Int = 4

  /** What the sender keeps with each entry of its order: `tags` are the marks of its transmissions so far. */
  private final case class Item(
      out: Outbound,
      priority: Priority,
      awaits: Awaits,
      outcome: Option[ActorRef[Outbox.Outcome]],
      notices: Option[ActorRef[Notice]],
      tag: Long,
      tags: Set[Long]
  )

  private type Order = CommandOrder[Item]

  /** The sender of robot `robotId`; `robot` owns the route; what leaves is counted in `sent` as it goes. */
  private[naogateway] def apply(robotId: Int, settings: CallSettings, robot: ActorRef[RobotActor.FromChild],
      sent: SentFigures = new SentFigures): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        Behaviors.withStash(settings.stashCapacity) { stash =>
          // The route is the robot actor's: asked for on every (re)start, pushed on every change.
          robot ! RobotActor.RouteWanted(context.self)
          new Sender(robotId, settings, sent, timers, stash).awaitingRoute
        }
      }
    }

  private final class Sender(
      robotId: Int,
      settings: CallSettings,
      sent: SentFigures,
      timers: TimerScheduler[Command],
      stash: StashBuffer[Command]
  ) {

    /** Before the robot actor has told the route: everything waits (bounded). */
    def awaitingRoute: Behavior[Command] = Behaviors
      .receiveMessage[Command] {
        case RouteChanged(route) =>
          val order = CommandOrder.empty[Item](MaxInFlight, settings.stashCapacity)
          stash.unstashAll(running(order, route, Long.MinValue))
        case s: Submit if stash.isFull =>
          val item = Item(s.out, s.priority, s.awaits, s.outcome, s.notices, 0L, Set.empty)
          refuse(s.key.getOrElse(0L), item, "the sender has no route yet")
          Behaviors.same
        case other =>
          if (!stash.isFull) stash.stash(other)
          Behaviors.same
      }
      .receiveSignal(signals(None))

    /** Sending: `nextKey` numbers the entries that come without a key of their own (below every call id). */
    private def running(order: Order, route: Route, nextKey: Long): Behavior[Command] =
      Behaviors
        .receiveMessage[Command] {
          case Submit(out, priority, key, awaits, outcome, notices) =>
            val k = key.getOrElse(nextKey)
            val item = Item(out, priority, awaits, outcome, notices, k, Set(k))
            // Slots are for callers' commands (those with notices); the gateway's own traffic replaces nothing.
            val call = out match {
              case Outbound.CallOut(c) if notices.isDefined => Some(c)
              case _                                        => None
            }
            val entry = CommandOrder.Entry(k, call.flatMap(RpcMethod.slotOf), priority == Priority.Safety, item,
              replaceable = call.flatMap(RpcMethod.of).forall(_.latestWins))
            val (next, steps) = order.submit(entry)
            val after = perform(next, steps, route, Some(k))
            if (after.waiting.exists(_.key == k)) notices.foreach(_ ! Notice.Queued(k))
            running(after, route, if (key.isEmpty) nextKey + 1 else nextKey)
          case Resend(key, out, tag) =>
            order.find(key) match {
              case Some(e) =>
                val again = e.payload.copy(out = out, tag = tag, tags = e.payload.tags + tag)
                // A waiting call only changes what it will carry; one in flight leaves again now.
                if (order.inFlightCall(key).isDefined) transmit(again, route)
                running(order.updated(key, again), route, nextKey)
              case None => Behaviors.same // given up meanwhile: its caller has its answer
            }
          case Finished(keys) =>
            keys.foreach(timers.cancel)
            val (next, steps) = order.completeAll(keys)
            running(perform(next, steps, route, None), route, nextKey)
          case HoldOver(key) =>
            val (next, steps) = order.complete(key)
            running(perform(next, steps, route, None), route, nextKey)
          case RouteChanged(newRoute) => running(order, newRoute, nextKey)
        }
        .receiveSignal(signals(Some(order)))

    /** Carries out the order's steps: supersessions first (their withdrawals reach the outbox before any send). */
    private def perform(
        order: Order, steps: Vector[CommandOrder.Step[Item]], route: Route, submitted: Option[Long]): Order =
      steps.foldLeft(order) {
        case (o, CommandOrder.Superseded(e, wasInFlight)) =>
          if (wasInFlight) {
            timers.cancel(e.key)
            route.outbox ! Outbox.Withdraw(robotId, e.payload.tags)
          }
          e.payload.notices.foreach(_ ! Notice.Superseded(e.key))
          o
        case (o, CommandOrder.Refused(e)) =>
          refuse(e.key, e.payload, s"${o.inFlight.size} calls in flight and ${o.waiting.size} waiting")
          o
        case (o, CommandOrder.Transmit(e)) =>
          val sent = transmit(e.payload, route)
          if (sent && !submitted.contains(e.key)) e.payload.notices.foreach(_ ! Notice.SentLate(e.key))
          e.payload.awaits match {
            case Awaits.Reply(hold) if sent =>
              hold.foreach(timers.startSingleTimer(e.key, HoldOver(e.key), _))
              o
            case _ =>
              // Sent and gone from the buffer, or never sent: its room is free again.
              val (next, more) = o.complete(e.key)
              perform(next, more, route, submitted)
          }
      }

    /** Encodes `item` for `route` and hands it to the outbox; false (its submitter told) when it cannot be encoded. */
    private def transmit(item: Item, route: Route): Boolean =
      RobotFrames.encode(robotId, item.out, route) match {
        case Right(bytes) =>
          sent.sent(bytes.length)
          route.outbox ! RobotFrames.send(robotId, item.out, bytes, route, item.priority, item.outcome, item.tag)
          true
        case Left(reason) =>
          item.outcome.foreach(_ ! Outbox.Dropped(item.tag, reason))
          false
      }

    private def refuse(key: Long, item: Item, reason: String): Unit =
      item.notices match {
        case Some(n) => n ! Notice.Refused(key, reason)
        case None    => item.outcome.foreach(_ ! Outbox.Dropped(item.tag, s"robot $robotId is overloaded: $reason"))
      }

    private def signals(order: Option[Order]): PartialFunction[(ActorContext[Command], Signal), Behavior[Command]] = {
      case (_, PreRestart | PostStop) =>
        // Submitters keep their own deadlines; those that wait for word from here hear it once.
        order.foreach { o =>
          val (_, flying, waiting) = o.drained
          (flying ++ waiting).foreach(e => e.payload.notices.foreach(_ ! Notice.Interrupted(e.key)))
        }
        stash.foreach {
          case s: Submit => s.key.foreach(k => s.notices.foreach(_ ! Notice.Interrupted(k)))
          case _         => ()
        }
        Behaviors.same
    }
  }
}
