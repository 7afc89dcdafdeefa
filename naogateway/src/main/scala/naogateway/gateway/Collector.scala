package naogateway.gateway

import java.net.InetSocketAddress

import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, Behavior}
import scala.concurrent.duration.FiniteDuration
import scala.reflect.ClassTag

import naogateway.access.RobotAccess

/** One question to every robot actor (`GetRobots`, `GetLinkStats`): asks each, and answers once all did or `timeout`
  * (`snapshot-timeout`) passed. A robot actor that did not answer in time (restarting) is listed by `missing`.
  */
private[naogateway] object Collector {

  /** What a collector receives: the robots' answers and its deadline. */
  sealed trait Message
  private final case class Got[A](robotId: Int, answer: A) extends Message
  private case object TimedOut extends Message

  def apply[A: ClassTag](robots: Map[Int, (ActorRef[RobotAccess.Question], InetSocketAddress)],
      timeout: FiniteDuration, replyTo: Vector[A] => Unit)(
      ask: ActorRef[A] => RobotAccess.Question, idOf: A => Int, missing: (Int, InetSocketAddress) => Option[A])
      : Behavior[Message] =
    Behaviors.setup[Message] { context =>
      Behaviors.withTimers { timers =>
        // One adapter for the one reply class this collector waits for.
        val got = context.messageAdapter[A](a => Got(idOf(a), a))
        robots.values.foreach { case (actor, _) => actor ! ask(got) }
        timers.startSingleTimer(TimedOut, timeout)
        def answer(known: Map[Int, A]): Behavior[Message] = {
          replyTo(robots.toVector.sortBy(_._1).flatMap { case (id, (_, address)) =>
            known.get(id).orElse(missing(id, address))
          })
          Behaviors.stopped
        }
        def collecting(known: Map[Int, A]): Behavior[Message] = Behaviors.receiveMessage {
          case g: Got[A @unchecked] =>
            val now = known.updated(g.robotId, g.answer)
            if (robots.keySet.forall(now.contains)) answer(now) else collecting(now)
          case TimedOut => answer(known)
        }
        collecting(Map.empty)
      }
    }
}
