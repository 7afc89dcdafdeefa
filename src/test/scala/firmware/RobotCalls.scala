package firmware

import scala.concurrent.duration._
import scala.concurrent.{Await, Future}
import scala.util.Try

import naogateway.RobotFailure

/** Waiting and call results for the specs that drive a firmware robot through the middleware (posix and qemu alike). */
object RobotCalls {

  /** Polls `condition` every 50 ms until it holds or `within` has passed; whether it held. */
  def poll(within: FiniteDuration)(condition: => Boolean): Boolean = {
    val deadline = within.fromNow
    var ok = condition
    while (!ok && deadline.hasTimeLeft()) { Thread.sleep(50); ok = condition }
    ok
  }

  /** The call's outcome, waiting at most 15 s. */
  def result[T](f: Future[T]): Either[Throwable, T] = Try(Await.result(f, 15.seconds)).toEither

  /** The robot's error text of a failed call, or a text saying the outcome was something else. */
  def robotError(r: Either[Throwable, _]): String = r match {
    case Left(RobotFailure.RobotError(_, e)) => e
    case other                               => s"not a robot error: $other"
  }
}
