package apps

import scala.concurrent.duration._
import scala.concurrent.{ExecutionContext, Future}
import scala.util.{Failure, Success}

import akka.actor.typed.ActorSystem
import akka.actor.typed.scaladsl.Behaviors
import akka.stream.scaladsl.Sink

import naogateway.RobotSnapshot
import naogateway.wire.RpcValue
import robotmiddleware.cluster.MiddlewareCluster
import robotmiddleware.{RobotClient, RobotInterface}

/** `./sbt "robotctl status"`: a command-line client that joins a running gateway's cluster as an app. */
object RobotCtl {

  /** What robotctl was asked to do. */
  sealed trait Request extends Product with Serializable

  /** The parsed command lines. */
  object Request {
    /** One line per robot. */
    case object Status extends Request
    /** One RPC call to a robot. */
    final case class Call(robotId: Int, module: String, method: String, params: Vector[RpcValue]) extends Request
    /** Prints a robot's status stream for a while. */
    final case class Watch(robotId: Int, seconds: Int) extends Request
  }

  val usage: String =
    """usage: robotctl status
      |       robotctl call <robotId> <module> <method> [param ...]   (numbers become floats, true/false flags, else text)
      |       robotctl watch <robotId> [seconds]                      (prints the robot's status stream; default 10 s)""".stripMargin

  /** Reads a parameter: a number, a truth value or a text. */
  def param(text: String): RpcValue =
    text.toFloatOption.map(RpcValue.Number(_): RpcValue)
      .orElse(text.toBooleanOption.map(RpcValue.Flag(_)))
      .getOrElse(RpcValue.Text(text))

  /** Parses the command line; a clear message when it is wrong. */
  def parse(args: Seq[String]): Either[String, Request] = args.toList match {
    case "status" :: Nil => Right(Request.Status)
    case "call" :: id :: module :: method :: params =>
      id.toIntOption.toRight(s"robot id '$id' is not a number").map(Request.Call(_, module, method, params.map(param).toVector))
    case "watch" :: id :: rest =>
      for {
        robotId <- id.toIntOption.toRight(s"robot id '$id' is not a number")
        seconds <- rest.headOption.fold[Either[String, Int]](Right(10))(s => s.toIntOption.filter(_ > 0).toRight(s"'$s' is not a number of seconds"))
      } yield Request.Watch(robotId, seconds)
    case _ => Left(usage)
  }

  /** One line per robot: id, address, online/offline, battery, posture, role, round-trip time. */
  def statusLine(r: RobotSnapshot, rttMillis: Option[Double]): String =
    f"${r.robotId}%-4d ${r.address.getAddress.getHostAddress + ":" + r.address.getPort}%-22s ${if (r.online) "online" else "offline"}%-8s " +
      f"${r.batteryVoltage.fold("-")(v => f"$v%.2f V")}%-8s ${r.posture.getOrElse("-")}%-8s ${r.role.getOrElse("-")}%-9s " +
      s"${rttMillis.fold("-")(v => f"$v%.1f ms")}"

  /** Runs `request` against the middleware; the text to print, or a failure. */
  def run(robot: RobotInterface, request: Request)(implicit system: ActorSystem[_]): Future[String] = {
    implicit val ec: ExecutionContext = system.executionContext
    request match {
      case Request.Status =>
        robot.robots().flatMap { robots =>
          Future.traverse(robots) { r =>
            robot.linkStats(r.robotId).map(_.rttMillis).runWith(Sink.headOption).map(_.flatten)
              .recover { case _ => None }
              .map(statusLine(r, _))
          }
        }.map(lines => ("id   address                status   battery  posture  role      rtt" +: lines).mkString("\n"))
      case Request.Call(id, module, method, params) =>
        val needs = robotmiddleware.Operation.RawCall(module, method, params).group
        needs.fold(Future.successful(akka.Done: Any))(g => robot.acquire(id, g))
          .flatMap(_ => robot.call(id, module, method, params: _*))
          .map(v => s"robot $id: $module.$method -> ${v.fold("(no value)")(_.toString)}")
          .andThen { case _ => needs.foreach(g => robot.release(id, g)) }
      case Request.Watch(id, seconds) =>
        robot.status(id).takeWithin(seconds.seconds)
          .runWith(Sink.foreach(s => println(statusLine(s, None))))
          .map(_ => s"watched robot $id for $seconds s")
    }
  }

  def main(args: Array[String]): Unit =
    parse(args.toSeq) match {
      case Left(message) =>
        System.err.println(message)
        System.exit(2)
      case Right(request) =>
        val node = MiddlewareCluster.start[Nothing](Behaviors.empty[Nothing], MiddlewareCluster.AppRole)
        implicit val system: ActorSystem[_] = node
        implicit val ec: ExecutionContext = system.executionContext
        val done = RobotClient(node, "robotctl", priority = 0).flatMap(robot => run(robot, request).andThen { case _ => robot.close() })
        done.onComplete { result =>
          val code = result match {
            case Success(text) => println(text); 0
            case Failure(e)    => System.err.println(s"robotctl: ${e.getMessage}"); 1
          }
          node.terminate()
          node.whenTerminated.onComplete(_ => System.exit(code))(ExecutionContext.global)
        }
    }
}
