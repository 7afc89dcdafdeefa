package apps.zeromq

import scala.concurrent.duration.FiniteDuration
import scala.concurrent.{ExecutionContext, Future, Promise}
import scala.util.control.NonFatal
import scala.util.{Failure, Success, Try}

import akka.actor.Cancellable
import akka.actor.typed.Scheduler

import naogateway.api.RobotFailure
import naogateway.wire.{ActuatorGroup, RpcMethod, RpcValue}
import robotmiddleware.RobotInterface

/** The requests a door (the ZeroMQ endpoint, the datagram door) is working on: each routed request handed to the
  * `RobotInterface`, answered exactly once (its answer, its timeout or the door's shutdown, whichever comes first), its
  * reply written to `A`, where it came from. One place for what both doors do with a request once they have read it.
  *
  * Its state has one owner: every method runs inside `owner` (the ZeroMQ loop's thread, the datagram door's lock), and
  * answers that complete elsewhere come back through it. `write` runs there too and must not block.
  *
  * @param door
  *   the door's name in error texts and logs ("ZeroMQ endpoint")
  * @param dispatcher
  *   where a request that waited for an earlier one starts (not on whatever thread handed the earlier one on)
  */
private[apps] final class RequestDesk[A](
    robots: RobotInterface,
    door: String,
    requestTimeout: FiniteDuration,
    owner: (() => Unit) => Unit,
    write: (A, Array[Byte]) => Unit,
    dispatcher: ExecutionContext,
    scheduler: Scheduler,
    servoLimits: robotmiddleware.ServoLimits
) {
  import RequestDesk.Pending

  private val log = org.slf4j.LoggerFactory.getLogger(classOf[RequestDesk[_]])
  // The interface's futures are composed on the thread that completes them: the steps are small, and an answer that is
  // there at once stays there at once (it leaves on the owner's thread without another hand-over).
  private implicit val ec: ExecutionContext = ExecutionContext.parasitic
  private var pending = Map.empty[Long, Pending[A]]
  /* Requests in progress per sender; an entry leaves with its sender's last request, so it holds no more than
   * `pending`. */
  private var bySender = Map.empty[A, Int]
  private var nextRequestId = 0L

  /** Requests being worked on. */
  def inFlight: Int = pending.size

  /** Requests of `from` being worked on. */
  def inFlightOf(from: A): Int = bySender.getOrElse(from, 0)

  /** Routes `request` of `from` and hands it on; its reply (or the error reply of a request that cannot be right) goes
    * to `from`.
    */
  def accept(from: A, request: EndpointRequest): Unit = {
    val callId = request.call.callId
    EndpointProtocol.route(request) match {
      case Left(error) => reply(from, request.robotId, callId, Left(error))
      case Right(route) =>
        val id = nextRequestId
        nextRequestId += 1
        val deadline = scheduler.scheduleOnce(requestTimeout, () => owner(() => timedOut(id)))
        pending = pending.updated(id, Pending(from, request.robotId, callId, request.call.name, deadline))
        bySender = bySender.updated(from, inFlightOf(from) + 1)
        if (log.isDebugEnabled) log.debug("{} request [{}]: {}", door, id, request.call)
        val answer = execute(route)
        answer.value match {
          // Answered already (an error, or an interface that had it at hand): out now, on this thread.
          case Some(result) => answered(id, result)
          // The thread that completes it hands the reply to the owner, no mailbox between.
          case None => answer.onComplete(r => owner(() => answered(id, r)))
        }
    }
  }

  /** Writes the reply to a request of `from` (also the error reply of one the door could not take). */
  def reply(from: A, robotId: Int, callId: Option[Long], result: Either[String, Answer]): Unit =
    write(from, EndpointProtocol.reply(robotId, callId, result))

  /** Requests still being worked on get an answer while the socket is still there to carry it. */
  def shutDown(): Unit = {
    pending.keys.foreach(id =>
      take(id).foreach(p => reply(p.from, p.robotId, p.callId, Left(s"endpoint error: the $door is shutting down"))))
  }

  private def take(id: Long): Option[Pending[A]] =
    pending.get(id).map { p =>
      pending -= id
      p.deadline.cancel()
      bySender = inFlightOf(p.from) match {
        case 1 => bySender - p.from
        case n => bySender.updated(p.from, n - 1)
      }
      p
    }

  private def answered(id: Long, result: Try[Answer]): Unit =
    take(id).foreach(p => reply(p.from, p.robotId, p.callId, result.toEither.left.map(EndpointProtocol.errorText)))

  // The late answer, if it ever comes, finds the request gone: each request is answered once.
  private def timedOut(id: Long): Unit =
    take(id).foreach(p =>
      reply(p.from, p.robotId, p.callId,
        Left(s"timeout: no answer to ${p.name} within ${requestTimeout.toMillis} ms at the endpoint")))

  // Where the last robot request was handed to the interface: the next one starts only after it, so requests reach
  // the middleware (and the robot) in the order they arrived, also when one first waits for its lease. One tail for
  // all robots: it holds no per-robot entry a client could grow.
  private var dispatched: Future[Unit] = Future.unit

  /** Starts `operate` once every earlier robot request has been handed on, after taking `group`'s lease when it needs
    * one. When nothing waits and no lease is needed it starts at once, on the owner's thread.
    */
  private def inOrder(robotId: Int, group: Option[ActuatorGroup])(operate: () => Future[Answer]): Future[Answer] = {
    val handedOn = Promise[Unit]()
    def start(ready: Try[Any]): Future[Answer] = {
      val answer = ready match {
        case Success(_) =>
          try operate()
          catch { case NonFatal(e) => Future.failed(e) }
        case Failure(e) => Future.failed(e)
      }
      handedOn.success(())
      answer
    }
    val answer = (dispatched.value, group) match {
      case (Some(_), None)    => start(Success(()))
      case (Some(_), Some(g)) => robots.acquire(robotId, g).transformWith(start)
      case (None, None)       => dispatched.transformWith(_ => start(Success(())))(dispatcher)
      case (None, Some(g)) =>
        dispatched.transformWith(_ => robots.acquire(robotId, g))(dispatcher).transformWith(start)
    }
    dispatched = handedOn.future
    answer
  }

  private def execute(route: Route): Future[Answer] = {
    val done = Answer(Some(RpcValue.Flag(true)))
    try route match {
        case Route.Robots =>
          robots.robots().map(all => Answer(Some(RpcValue.Items(all.map(s => RpcValue.UInt(s.robotId.toLong))))))
        case Route.Status(robotId) =>
          robots.robots().flatMap(_.find(_.robotId == robotId) match {
            case Some(s) if s.online =>
              // The keep-alive may be up to an interval old: a stop or posture just answered is not in it yet, the
              // robot's own answer is (a read, no lease). Without one, the keep-alive's posture stands.
              robots.call(robotId, RpcMethod.GetPosture.module, RpcMethod.GetPosture.method).transform {
                case Success(Some(RpcValue.Text(now))) => Success(RequestDesk.status(s.copy(posture =
                        Some(naogateway.wire.Posture.reported(now)))))
                case _ => Success(RequestDesk.status(s))
              }
            case Some(s) => Future.successful(RequestDesk.status(s))
            case None    => Future.failed(RobotFailure.UnknownRobot(robotId))
          })
        case Route.Servos(robotId) =>
          robots.robots().flatMap(_.find(_.robotId == robotId) match {
            case Some(s) => Future.successful(RequestDesk.servos(s, servoLimits))
            case None    => Future.failed(RobotFailure.UnknownRobot(robotId))
          })
        case Route.Acquire(robotId, groups) => robots.acquire(robotId, groups: _*).map(_ => done)
        case Route.Release(robotId, groups) =>
          inOrder(robotId, None) { () =>
            robots.release(robotId, groups: _*)
            Future.successful(done)
          }
        case Route.Send(robotId, operation) =>
          inOrder(robotId, operation.group)(() => robots.send(robotId, operation).map(_ => done))
        case Route.Execute(robotId, operation) =>
          import robotmiddleware.Operation._
          inOrder(robotId, operation.group) { () =>
            operation match {
              case Walk(vx, vy, omega)  => robots.walk(robotId, vx, vy, omega).map(_ => done)
              case Stop()               => robots.stop(robotId).map(_ => done)
              case Head(pan, tilt)      => robots.head(robotId, pan, tilt).map(_ => done)
              case Arms(ls, le, rs, re) => robots.arms(robotId, ls, le, rs, re).map(_ => done)
              case Posture(p) =>
                robots.posture(robotId, p).map(reached => Answer(Some(RpcValue.Text(reached.name))))
              case Say(text) => robots.say(robotId, text).map(_ => done)
              case RawCall(module, method, params) =>
                robots.call(robotId, module, method, params: _*).map(Answer(_))
            }
          }
      }
    catch { case NonFatal(e) => Future.failed(e) }
  }
}

private[apps] object RequestDesk {

  /** The answer to `gateway.status`: `[online, link quality]`, and the snapshot the reply carries. */
  def status(s: naogateway.api.RobotSnapshot): Answer =
    Answer(Some(RpcValue.Items(Vector(RpcValue.Flag(s.online), RpcValue.Text(s.quality.name)))), Some(s))

  /** The answer to `gateway.servos`: `[hot ids, low-voltage ids]` by `limits`, and the telemetry the reply carries
    * (none before the robot's first).
    */
  def servos(s: naogateway.api.RobotSnapshot, limits: robotmiddleware.ServoLimits): Answer = {
    val readings = s.servos.fold(Vector.empty[naogateway.api.ServoReading])(_.servos)
    def ids(marked: naogateway.api.ServoReading => Boolean) =
      RpcValue.Items(readings.filter(marked).map(r => RpcValue.UInt(r.id.toLong)))
    Answer(Some(RpcValue.Items(Vector(ids(limits.hot), ids(limits.lowVoltage)))), servos = s.servos)
  }

  /** A request being worked on: where its reply goes, what it must echo, and its deadline's timer. */
  final case class Pending[A](from: A, robotId: Int, callId: Option[Long], name: String, deadline: Cancellable)
}
