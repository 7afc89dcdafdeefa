package apps.zeromq

import scala.util.Try

import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, Behavior}

import robotmiddleware.{RobotClient, RobotInterface, RobotMiddleware}

/** The first state of a door for programs in other languages (the ZeroMQ endpoint, the datagram door): it registers as
  * an app with the middleware, holds what arrives meanwhile (up to 64 messages, more are dropped with a warning), and
  * serves once registered; a refused registration fails the actor, whose parent decides what follows.
  */
private[apps] object Registering {

  /** Registers as `appName` at `priority`; `registered` wraps the outcome into the door's own message, `outcome`
    * recognises it again, and `serving` is the door once it has its `RobotInterface`. `door` names it in messages.
    */
  def apply[C](middleware: ActorRef[RobotMiddleware.Command], appName: String, priority: Int, door: String)(
      registered: Try[RobotInterface] => C, outcome: PartialFunction[C, Try[RobotInterface]])(
      serving: RobotInterface => Behavior[C]): Behavior[C] =
    Behaviors.setup { context =>
      Behaviors.withStash(64) { stash =>
        context.pipeToSelf(RobotClient.connect(context.system, middleware, appName, priority))(registered)
        Behaviors.receiveMessage { message =>
          outcome.lift(message) match {
            case Some(result) =>
              val robots =
                result.fold(e => throw new IllegalStateException(s"$door cannot register with the middleware: $e", e),
                  identity)
              stash.unstashAll(serving(robots))
            case None =>
              if (stash.isFull) context.log.warn("{}: message dropped while registering", door)
              else stash.stash(message)
              Behaviors.same
          }
        }
      }
    }
}
