package apps

import naogateway.wire.ActuatorGroup

import java.io.{InputStream, PrintStream}

import scala.concurrent.{ExecutionContext, Future}
import scala.util.{Failure, Success, Try}

import akka.actor.typed.scaladsl.Behaviors
import naogateway.wire.Posture
import robotmiddleware.RobotClient
import robotmiddleware.cluster.MiddlewareCluster

import robotmiddleware.RobotInterface

/** Keyboard teleoperation of one robot: keys become walk, head and posture commands through `RobotInterface`. */
object Teleop {

  /** What one key asks for. */
  sealed trait Action extends Product with Serializable

  /** The actions of the keyboard map. */
  object Action {

    /** Walk at this velocity (m/s, m/s, rad/s). */
    final case class Walk(vx: Double, vy: Double, omega: Double) extends Action

    /** Stop walking. */
    case object Stop extends Action

    /** Turn the head by these angles (rad). */
    final case class HeadBy(dPan: Double, dTilt: Double) extends Action

    /** Go to this posture. */
    final case class Posture(target: naogateway.wire.Posture.Target) extends Action

    /** Stop the robot and leave. */
    case object Quit extends Action
  }

  /** The keyboard map, shown by `help`. */
  val keys: Vector[(Char, String, Action)] = Vector(
    ('w', "walk forward", Action.Walk(0.2, 0.0, 0.0)),
    ('s', "walk backward", Action.Walk(-0.1, 0.0, 0.0)),
    ('a', "turn left", Action.Walk(0.0, 0.0, 0.6)),
    ('d', "turn right", Action.Walk(0.0, 0.0, -0.6)),
    ('q', "step left", Action.Walk(0.0, 0.1, 0.0)),
    ('e', "step right", Action.Walk(0.0, -0.1, 0.0)),
    (' ', "stop", Action.Stop),
    ('h', "head left", Action.HeadBy(0.2, 0.0)),
    ('l', "head right", Action.HeadBy(-0.2, 0.0)),
    ('k', "head up", Action.HeadBy(0.0, 0.1)),
    ('j', "head down", Action.HeadBy(0.0, -0.1)),
    ('1', "sit", Action.Posture(Posture.Sit)),
    ('2', "stand", Action.Posture(Posture.Stand)),
    ('3', "crouch", Action.Posture(Posture.Crouch)),
    ('x', "quit", Action.Quit)
  )

  private val byKey: Map[Char, Action] = keys.map(k => k._1 -> k._3).toMap

  /** The action of a key, if the key has one. */
  def action(key: Char): Option[Action] = byKey.get(key.toLower)

  /** The key map as text. */
  def help: String =
    keys.map { case (k, text, _) => s"  ${if (k == ' ') "space" else k.toString}  $text" }.mkString("\n")

  /** Reads keys from `in` until `x` or the end of input, steering `robotId`; every outcome is printed, no failure ends
    * the session. Reads block: run it on a thread of its own, never inside an actor.
    */
  def run(robot: RobotInterface, robotId: Int, in: InputStream, out: PrintStream)(
      implicit ec: ExecutionContext): Unit = {
    // Outcomes are printed when they arrive; the key loop never waits for the robot.
    def report(what: String, f: Future[_]): Unit =
      f.onComplete {
        case scala.util.Success(_) => out.println(s"robot $robotId: $what")
        // The failure may carry the robot's own error text: shown with its control characters replaced.
        case scala.util.Failure(e) =>
          out.println(s"robot $robotId: $what failed: ${naogateway.api.Printable.text(e.getMessage)}")
      }

    report("leases taken", robot.acquire(robotId, ActuatorGroup.Walk, ActuatorGroup.Head))
    out.println(help)
    var pan = 0.0
    var tilt = 0.0
    var running = true
    while (running) {
      val c = in.read()
      if (c < 0) running = false
      else
        action(c.toChar).foreach {
          case Action.Quit => running = false
          case Action.Walk(vx, vy, omega) =>
            report(f"walk $vx%.1f $vy%.1f $omega%.1f", robot.walk(robotId, vx, vy, omega))
          case Action.Stop => report("stop", robot.stop(robotId))
          case Action.HeadBy(dp, dt) =>
            pan = math.max(-2.0, math.min(2.0, pan + dp))
            tilt = math.max(-0.6, math.min(0.5, tilt + dt))
            report(f"head $pan%.1f $tilt%.1f", robot.head(robotId, pan, tilt))
          case Action.Posture(target) => report(s"posture ${target.name}", robot.posture(robotId, target))
        }
    }
    report("stop", robot.stop(robotId))
    robot.release(robotId, ActuatorGroup.Walk, ActuatorGroup.Head)
  }

  /** `./sbt "apps/runMain apps.Teleop <robotId>"`: joins a running gateway as an app with priority 5 and steers the
    * robot from the keyboard until `x`. On a terminal the keys act at once (raw mode); through sbt, end keys with
    * Enter.
    */
  def main(args: Array[String]): Unit = {
    val robotId = args.headOption.flatMap(_.toIntOption).getOrElse {
      System.err.println("usage: teleop <robotId>")
      sys.exit(2)
    }
    // Logback is set up before the actor systems' threads log at once; otherwise SLF4J queues their first lines and
    // prints a warning about replaying them on every start.
    org.slf4j.LoggerFactory.getILoggerFactory
    // A node off loopback without the team's TLS files does not start (docs/cluster.md): one line, no stack trace.
    val node =
      try MiddlewareCluster.start[Nothing](Behaviors.empty, MiddlewareCluster.AppRole)
      catch {
        case e: IllegalArgumentException =>
          System.err.println(s"teleop: ${e.getMessage}")
          sys.exit(2)
      }
    implicit val ec: ExecutionContext = node.executionContext
    val raw = System.console() != null && Try(stty("-icanon -echo min 1")).isSuccess
    RobotClient(node, "teleop", priority = 5).onComplete {
      case Success(robot) =>
        // The key loop blocks on stdin: it gets a thread of its own, never an actor's.
        val loop = new Thread(() => {
            try run(robot, robotId, System.in, System.out)
            finally {
              if (raw) Try(stty("sane"))
              robot.close()
              node.terminate()
            }
          }, "teleop-keys")
        loop.start()
      case Failure(e) =>
        System.err.println(s"teleop: ${e.getMessage}")
        if (raw) Try(stty("sane"))
        node.terminate()
    }
  }

  private def stty(mode: String): Unit = {
    val process = new ProcessBuilder("sh", "-c", s"stty $mode < /dev/tty").inheritIO().start()
    if (process.waitFor() != 0) throw new IllegalStateException("stty failed")
  }
}
