package apps.web

import scala.concurrent.duration._
import scala.concurrent.{ExecutionContext, Future}
import scala.util.{Failure, Success}

import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, Behavior, PostStop}
import spray.json._

import naogateway.wire.{ActuatorGroup, Posture}
import robotmiddleware.{RobotClient, RobotInterface, RobotMiddleware}

/** The web view's control panel (docs/web.md, "The control panel"): pages steer robots through the `RobotInterface` as
  * one app, with the `walk` lease as teleop takes it. Off unless `apps.web.control.enabled`; refused in competition
  * mode; only behind the token. A robot walking from a page stops when no command came for `deadman`: a phone that lost
  * the network never leaves a robot walking.
  */
object WebControl {

  /** Whether the panel serves, and if not, why (for the page and the log). */
  final case class Availability(enabled: Boolean, reason: String)

  /** What the panel accepts. */
  sealed trait Command

  /** A page's request (walk or stop), answered with one JSON line. */
  final case class Request(request: Drive, replyTo: ActorRef[String]) extends Command

  /** What a page may ask: walk with velocities (clamped), or stop. */
  sealed trait Drive

  /** Walk with these velocities (m/s, m/s, rad/s), already clamped. */
  final case class Walk(robotId: Int, vx: Double, vy: Double, omega: Double) extends Drive

  /** Stop walking. */
  final case class Stop(robotId: Int) extends Drive

  /** A request the panel cannot read, and why. */
  final case class Bad(reason: String) extends Drive

  private final case class Connected(robots: RobotInterface) extends Command
  private final case class ConnectFailed(reason: Throwable) extends Command
  private case object Check extends Command
  private final case class Leased(robotId: Int) extends Command

  /** The fastest a page may ask for, as teleop's keys: m/s forward, m/s sideways, rad/s turning. */
  val MaxForward: Double = 0.2
  val MaxSideways: Double = 0.1
  val MaxTurn: Double = 0.6

  /** A page's JSON request as a drive (total: anything else is `Bad`). */
  def drive(text: String): Drive =
    scala.util.Try(text.parseJson.asJsObject.fields).toOption.fold[Drive](Bad("not a JSON object")) { f =>
      def num(k: String): Option[Double] = f.get(k) match {
        case Some(JsNumber(n)) if n.abs < 1000 => Some(n.toDouble)
        case _                                 => None
      }
      def clamp(v: Double, max: Double) = math.max(-max, math.min(max, v))
      val robot = num("robot").filter(r => r.isValidInt && r >= 0).map(_.toInt)
      (f.get("op"), robot) match {
        case (Some(JsString("walk")), Some(id)) =>
          (for (vx <- num("vx"); vy <- num("vy"); om <- num("omega"))
            yield Walk(id, clamp(vx, MaxForward), clamp(vy, MaxSideways), clamp(om, MaxTurn)))
            .getOrElse(Bad("walk needs vx, vy and omega"))
        case (Some(JsString("stop")), Some(id)) => Stop(id)
        case (_, None)                          => Bad("a request needs a robot")
        case _                                  => Bad("op must be walk or stop")
      }
    }

  /** The panel for `middleware`'s robots, or one refusing every request with `availability.reason`. */
  def apply(middleware: ActorRef[RobotMiddleware.Command], settings: WebSettings.Control, availability: Availability)
      : Behavior[Command] =
    if (!availability.enabled) refusing(availability.reason)
    else
      Behaviors.setup { context =>
        context.pipeToSelf(RobotClient.connect(context.system, middleware, settings.appName, settings.priority)) {
          case Success(r) => Connected(r)
          case Failure(e) => ConnectFailed(e)
        }
        Behaviors.withStash(64) { stash =>
          Behaviors.receiveMessage {
            case Connected(robots) =>
              Behaviors.withTimers { timers =>
                timers.startTimerWithFixedDelay(Check, settings.deadman / 4)
                stash.unstashAll(driving(robots, settings, Map.empty, Set.empty))
              }
            case ConnectFailed(e) =>
              context.log.error("Web control panel: cannot register with the middleware", e)
              stash.unstashAll(refusing("the control panel found no middleware"))
            case other =>
              if (!stash.isFull) stash.stash(other)
              Behaviors.same
          }
        }
      }

  private def answer(ok: Boolean, message: String): String =
    // A failure's message may carry a robot's error text: no control character reaches the page.
    JsObject("op" -> JsString("result"), "ok" -> JsBoolean(ok),
      "message" -> JsString(naogateway.api.Printable.text(message))).compactPrint

  private def refusing(reason: String): Behavior[Command] = Behaviors.receiveMessage {
    case Request(_, replyTo) =>
      replyTo ! answer(ok = false, reason)
      Behaviors.same
    case _ => Behaviors.same
  }

  /** `walking`: robots walking from a page, with when their last command came; `leased`: robots whose lease we hold. */
  private def driving(robots: RobotInterface, settings: WebSettings.Control, walking: Map[Int, Long], leased: Set[Int])
      : Behavior[Command] =
    Behaviors.setup { context =>
      implicit val ec: ExecutionContext = context.executionContext
      def reply(replyTo: ActorRef[String], what: String, f: Future[_]): Unit = f.onComplete {
        case Success(_) => replyTo ! answer(ok = true, what)
        case Failure(e) => replyTo ! answer(ok = false, s"$what: ${e.getMessage}")
      }
      Behaviors.receiveMessage[Command] {
        case Request(Walk(id, vx, vy, omega), replyTo) =>
          // The lease first (as teleop takes it), then standing up from sit or crouch, then the walk.
          val lease =
            if (leased(id)) Future.unit else robots.acquire(id, ActuatorGroup.Walk).map(_ => context.self ! Leased(id))
          val walk = lease.flatMap { _ =>
            robots.walk(id, vx, vy, omega).recoverWith { case _ =>
              robots.posture(id, Posture.Stand).flatMap(_ => robots.walk(id, vx, vy, omega))
            }
          }
          reply(replyTo, f"robot $id walks $vx%.2f $vy%.2f $omega%.2f", walk)
          driving(robots, settings, walking.updated(id, System.nanoTime()), leased)
        case Request(Stop(id), replyTo) =>
          reply(replyTo, s"robot $id stops", if (leased(id)) robots.stop(id) else Future.unit)
          driving(robots, settings, walking - id, leased)
        case Request(Bad(reason), replyTo) =>
          replyTo ! answer(ok = false, reason)
          Behaviors.same
        case Leased(id) => driving(robots, settings, walking, leased + id)
        case Check =>
          val now = System.nanoTime()
          val stale = walking.collect { case (id, at) if now - at > settings.deadman.toNanos => id }
          stale.foreach { id =>
            context.log.info("Web control panel: no command for robot {} within {}, it stops", id, settings.deadman)
            robots.stop(id)
          }
          driving(robots, settings, walking -- stale, leased)
        case _ => Behaviors.same
      }.receiveSignal { case (_, PostStop) =>
        // Closing the session releases every lease and stops the robots it walked.
        robots.close()
        Behaviors.same
      }
    }

  /** How long a page's request may take. */
  val RequestTimeout: FiniteDuration = 10.seconds
}
