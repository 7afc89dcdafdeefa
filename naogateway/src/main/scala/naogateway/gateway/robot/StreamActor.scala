package naogateway.gateway.robot

import scala.concurrent.duration._

import akka.actor.typed.scaladsl.{Behaviors, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior}

import naogateway.wire.stream.{SecureStream, StreamStats, StreamSettings}
import naogateway.api.Priority

/** The gateway's end of one robot's secure stream (docs/protocol.md §11): reliable, ordered payloads over the lossy
  * link.
  */
object StreamActor {

  /** What the stream endpoint accepts. */
  sealed trait Command

  /** Sends `payload` reliably; `deadline` (from now) lets stale data expire instead of being resent for ever. */
  private[naogateway] final case class Send(payload: Array[Byte], deadline: Option[FiniteDuration] = None,
      replyTo: Option[ActorRef[SendResult]] = None)
      extends Command

  /** Delivers every payload received from the robot, in order, to `subscriber`. */
  private[naogateway] final case class Subscribe(subscriber: ActorRef[Received]) extends Command

  /** Answers with the stream's stats. */
  private[naogateway] final case class GetStats(replyTo: ActorRef[StreamStats]) extends Command

  /** A segment from the robot's address. */
  private[naogateway] final case class SegmentReceived(bytes: Array[Byte]) extends Command

  /** The robot restarted with fresh sequence numbers: start the stream afresh, keeping unacknowledged payloads. */
  private[naogateway] case object Reset extends Command

  private case object Tick extends Command
  private final case class SubscriberGone(subscriber: ActorRef[Received]) extends Command

  /** A payload from the robot. */
  final case class Received(robotId: Int, payload: Array[Byte])

  /** How a sent payload ended. */
  sealed trait SendResult extends Product with Serializable

  /** The robot acknowledged it. */
  case object Acknowledged extends SendResult

  /** Its deadline passed before the robot acknowledged it. */
  case object Expired extends SendResult

  /** Not taken (empty, too large, queue full). */
  final case class Refused(reason: String) extends SendResult

  private case object TickKey

  /** The endpoint for robot `robotId`, sending segments through the robot's one sender. */
  private[naogateway] def apply(
      robotId: Int, settings: StreamSettings, sender: ActorRef[NoResponseActor.Command]): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        val endpoint = new Endpoint(robotId, sender, timers, context)
        val fresh = SecureStream.initial(settings, System.nanoTime())
        endpoint.schedule(fresh)
        endpoint.running(fresh, 0L, Map.empty, Set.empty)
      }
    }

  private final class Endpoint(
      robotId: Int,
      sender: ActorRef[NoResponseActor.Command],
      timers: TimerScheduler[Command],
      context: akka.actor.typed.scaladsl.ActorContext[Command]
  ) {
    private def apply(step: SecureStream.Step, waiting: Map[Long, ActorRef[SendResult]],
        subscribers: Set[ActorRef[Received]]): Map[Long, ActorRef[SendResult]] = {
      var left = waiting
      step.outputs.foreach {
        case SecureStream.Transmit(datagram) =>
          // A segment leaves the robot's buffer as it goes: the stream's own window bounds how many are unacknowledged.
          sender ! NoResponseActor.Submit(RobotFrames.Outbound.SegmentOut(datagram), Priority.Command, None,
            NoResponseActor.Awaits.Nothing)
        case SecureStream.Deliver(payload) => subscribers.foreach(_ ! Received(robotId, payload))
        case SecureStream.Acknowledged(id) =>
          left.get(id).foreach(_ ! Acknowledged)
          left -= id
        case SecureStream.Expired(id) =>
          left.get(id).foreach(_ ! Expired)
          left -= id
      }
      schedule(step.state)
      left
    }

    /** Keeps the one timer at the state's next due time; a fresh or idle stream has none and sends nothing. */
    def schedule(stream: SecureStream): Unit =
      stream.nextTimerAt match {
        case Some(at) => timers.startSingleTimer(TickKey, Tick, math.max(0L, at - System.nanoTime()).nanos)
        case None     => timers.cancel(TickKey)
      }

    def running(stream: SecureStream, lastId: Long, waiting: Map[Long, ActorRef[SendResult]],
        subscribers: Set[ActorRef[Received]]): Behavior[Command] = Behaviors.receiveMessage[Command] {
      case Send(payload, deadline, replyTo) =>
        val now = System.nanoTime()
        val id = lastId + 1
        stream.send(payload, id, deadline.map(now + _.toNanos), now) match {
          case Left(refused) =>
            replyTo.foreach(_ ! Refused(refused.describe))
            Behaviors.same
          case Right(step) =>
            val w = apply(step, replyTo.fold(waiting)(r => waiting.updated(id, r)), subscribers)
            running(step.state, id, w, subscribers)
        }
      case SegmentReceived(bytes) =>
        val step = stream.receive(bytes, System.nanoTime())
        running(step.state, lastId, apply(step, waiting, subscribers), subscribers)
      case Tick =>
        val step = stream.tick(System.nanoTime())
        running(step.state, lastId, apply(step, waiting, subscribers), subscribers)
      case Reset =>
        context.log.info("Robot [{}]: secure stream reset", robotId)
        val step = stream.reset(System.nanoTime())
        running(step.state, lastId, apply(step, waiting, subscribers), subscribers)
      case Subscribe(subscriber) =>
        context.watchWith(subscriber, SubscriberGone(subscriber))
        running(stream, lastId, waiting, subscribers + subscriber)
      case SubscriberGone(subscriber) =>
        running(stream, lastId, waiting, subscribers - subscriber)
      case GetStats(replyTo) =>
        replyTo ! stream.stats
        Behaviors.same
    }.receiveSignal {
      case (_, akka.actor.typed.PreRestart | akka.actor.typed.PostStop) =>
        // Nothing is forgotten: senders still waiting learn that their payload's fate is unknown.
        waiting.values.foreach(_ ! Refused("stream endpoint restarted before the robot acknowledged"))
        Behaviors.same
    }
  }
}
