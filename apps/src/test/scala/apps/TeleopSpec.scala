package apps

import naogateway.api.RobotFailure

import naogateway.wire.ActuatorGroup

import java.io.{ByteArrayInputStream, ByteArrayOutputStream, PrintStream}

import scala.concurrent.{ExecutionContext, Future}

import akka.stream.scaladsl.Source
import akka.{Done, NotUsed}
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.api.{LinkStats, RobotEvent, RobotSnapshot, VisionFrame}
import naogateway.wire.RpcValue
import naogateway.wire.gamecontroller.GameControlData
import naogateway.wire.Posture
import robotmiddleware.{AppEvent, RobotInterface}

class TeleopSpec extends AnyWordSpec with Matchers {

  /** Records every command; head commands fail, to show a failure does not end the session. */
  private final class Recorder extends RobotInterface {
    @volatile var log: Vector[String] = Vector.empty
    private def ok(entry: String): Future[Done] = { log :+= entry; Future.successful(Done) }
    def appName: String = "teleop"
    def robots(): Future[Vector[RobotSnapshot]] = Future.successful(Vector.empty)
    def acquire(robotId: Int, groups: ActuatorGroup*): Future[Done] = ok(s"acquire ${groups.map(_.name).mkString(",")}")
    def release(robotId: Int, groups: ActuatorGroup*): Unit = log :+= s"release ${groups.map(_.name).mkString(",")}"
    def walk(robotId: Int, vx: Double, vy: Double, omega: Double): Future[Done] = ok(s"walk $vx $vy $omega")
    def stop(robotId: Int): Future[Done] = ok("stop")
    def head(robotId: Int, pan: Double, tilt: Double): Future[Done] = {
      log :+= f"head $pan%.1f $tilt%.1f"
      Future.failed(RobotFailure.RobotError(robotId, "out of range"))
    }
    def arms(robotId: Int, a: Double, b: Double, c: Double, d: Double): Future[Done] = ok("arms")
    def posture(robotId: Int, target: Posture.Target): Future[Posture] = {
      log :+= s"posture ${target.name}"; Future.successful(target)
    }
    def say(robotId: Int, text: String): Future[Done] = ok(s"say $text")
    def call(robotId: Int, module: String, method: String, params: RpcValue*): Future[Option[RpcValue]] =
      Future.successful(None)
    def send(robotId: Int, operation: robotmiddleware.Operation): Future[Done] = ok(s"send ${operation.name}")
    def status(robotId: Int): Source[RobotSnapshot, NotUsed] = Source.empty
    def allStatus: Source[RobotSnapshot, NotUsed] = Source.empty
    def vision(robotId: Int, grid: Boolean): Source[VisionFrame, NotUsed] = Source.empty
    def linkStats(robotId: Int): Source[LinkStats, NotUsed] = Source.empty
    def gameState: Source[GameControlData, NotUsed] = Source.empty
    def robotEvents: Source[RobotEvent, NotUsed] = Source.empty
    def appEvents: Source[AppEvent, NotUsed] = Source.empty
    def holds(): Future[Vector[robotmiddleware.RobotHolds]] = Future.successful(Vector.empty)
    def close(): Unit = ()
  }

  "Teleop" should {
    "turn keys into commands, survive a failing command, and stop and release on quit" in {
      val robot = new Recorder
      val out = new ByteArrayOutputStream()
      Teleop.run(robot, 2, new ByteArrayInputStream("2wa h? x w".getBytes), new PrintStream(out))(
        ExecutionContext.global)
      robot.log shouldBe Vector("acquire walk,head", "posture stand", "walk 0.2 0.0 0.0", "walk 0.0 0.0 0.6", "stop",
        "head 0.2 0.0",
        "stop", "stop", "release walk,head") // the space before x stops, and quitting stops once more
      org.scalatest.concurrent.Eventually.eventually {
        out.toString should include("robot 2: head 0.2 0.0 failed: robot 2: out of range")
      }
    }
    "stop the robot when the input ends" in {
      val robot = new Recorder
      Teleop.run(robot, 1, new ByteArrayInputStream("w".getBytes), new PrintStream(new ByteArrayOutputStream()))(
        ExecutionContext.global)
      robot.log.takeRight(2) shouldBe Vector("stop", "release walk,head")
    }
  }
}
