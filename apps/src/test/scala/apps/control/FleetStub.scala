package apps.control

import naogateway.api.RobotFailure

import naogateway.wire.ActuatorGroup

import java.net.InetSocketAddress
import java.util.concurrent.ConcurrentLinkedQueue

import scala.concurrent.Future
import scala.jdk.CollectionConverters._

import akka.stream.scaladsl.Source
import akka.{Done, NotUsed}

import naogateway.wire.{Posture, RpcValue}
import naogateway.wire.gamecontroller.GameControlData
import naogateway.api.{ClockEstimate, LinkQuality, LinkStats, RobotEvent, RobotSnapshot, VisionFrame}
import robotmiddleware._

/** A `RobotInterface` of `robots` robots (ids 1 to `robots`) that answer at once, for the control port's tests: robot
  * 5's calls fail, robots above `robots` are unknown, and every lease taken and given back is recorded.
  */
final class FleetStub(robots: Int) extends RobotInterface {

  /** Leases and calls in order: "acquire 2 walk", "call 2 motion.walk", "release 2 walk". */
  val seen = new ConcurrentLinkedQueue[String]()

  def history: Vector[String] = seen.asScala.toVector

  private def snapshot(id: Int) =
    RobotSnapshot(
      id,
      new InetSocketAddress("127.0.0.1", 20000 + id),
      role = Some("striker"),
      posture = Some(Posture.Sit),
      batteryVoltage = Some(12.25),
      online = id % 10 != 0,
      quality = if (id % 10 != 0) LinkQuality.Good else LinkQuality.Offline,
      clock = if (id % 10 != 0) Some(ClockEstimate(5000L, 7000000000L, 1.0 / (1.0 + 250e-6), 1.4, 0.0001, 40)) else None
    )

  private def known(id: Int): Either[Throwable, Int] =
    if (id >= 1 && id <= robots) Right(id) else Left(RobotFailure.UnknownRobot(id))

  def appName: String = "fleet-stub"
  def robots(): Future[Vector[RobotSnapshot]] = Future.successful((1 to robots).map(snapshot).toVector)

  def acquire(robotId: Int, groups: ActuatorGroup*): Future[Done] = {
    seen.add(s"acquire $robotId ${groups.map(_.name).mkString(",")}")
    Future.fromTry(known(robotId).map(_ => Done).toTry)
  }
  def release(robotId: Int, groups: ActuatorGroup*): Unit = {
    seen.add(s"release $robotId ${groups.map(_.name).mkString(",")}"); ()
  }

  def call(robotId: Int, module: String, method: String, params: RpcValue*): Future[Option[RpcValue]] = {
    seen.add(s"call $robotId $module.$method")
    known(robotId) match {
      case Left(e)  => Future.failed(e)
      case Right(5) => Future.failed(RobotFailure.RobotError(5, "no such method"))
      case Right(_) => Future.successful(Some(RpcValue.Text(s"$module.$method(${params.mkString(",")})")))
    }
  }

  private def unused = Future.failed(new UnsupportedOperationException("not served by the control port"))
  def walk(robotId: Int, vx: Double, vy: Double, omega: Double): Future[Done] = unused
  def send(robotId: Int, operation: robotmiddleware.Operation): Future[Done] = unused
  def stop(robotId: Int): Future[Done] = unused
  def head(robotId: Int, pan: Double, tilt: Double): Future[Done] = unused
  def arms(robotId: Int, ls: Double, le: Double, rs: Double, re: Double): Future[Done] = unused
  def posture(robotId: Int, target: Posture.Target): Future[Posture] = unused
  def say(robotId: Int, text: String): Future[Done] = unused

  def status(robotId: Int): Source[RobotSnapshot, NotUsed] =
    if (robotId >= 1 && robotId <= robots) Source(List.fill(3)(snapshot(robotId))) else Source.empty
  def allStatus: Source[RobotSnapshot, NotUsed] = Source.empty
  def vision(robotId: Int, grid: Boolean): Source[VisionFrame, NotUsed] = Source.empty
  def linkStats(robotId: Int): Source[LinkStats, NotUsed] =
    Source.single(LinkStats(robotId, 10, 10, 100, 100, Some(1.5), 0.25, 0, Map.empty))
  def gameState: Source[GameControlData, NotUsed] = Source.empty
  def robotEvents: Source[RobotEvent, NotUsed] = Source.empty
  def appEvents: Source[AppEvent, NotUsed] = Source.empty

  /** Robot 2's walk is held by "teleop", robot 3 is held safe. */
  def holds(): Future[Vector[RobotHolds]] =
    Future.successful(Vector(RobotHolds(2, Map(ActuatorGroup.Walk -> "teleop"), None),
        RobotHolds(3, Map.empty, Some("battery low: 10.70 V; it clears by itself"))).filter(_.robotId <= robots))
  def close(): Unit = { seen.add("close"); () }
}
