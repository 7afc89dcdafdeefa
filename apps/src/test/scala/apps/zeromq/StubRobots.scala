package apps.zeromq

import naogateway.api.RobotFailure

import naogateway.wire.ActuatorGroup

import java.net.InetSocketAddress
import java.util.concurrent.ConcurrentLinkedQueue
import java.util.concurrent.atomic.AtomicInteger

import scala.concurrent.duration._
import scala.concurrent.{ExecutionContext, Future, Promise}
import scala.jdk.CollectionConverters._

import akka.actor.typed.ActorSystem
import akka.stream.scaladsl.Source
import akka.{Done, NotUsed}

import naogateway.wire.gamecontroller.{GameControlData, GameControllerCodec}
import naogateway.wire.{HaViMoRegion, Posture, RpcValue}
import naogateway.api.{LinkQuality, LinkStats, RobotEvent, RobotSnapshot, VisionFrame}
import robotmiddleware._

/** A `RobotInterface` whose robots answer from a script: robot 7 works; the others fail in one way each, so the
  * endpoint's mapping, error texts, concurrency and publishing can be tested without a gateway.
  */
final class StubRobots(system: ActorSystem[_]) extends RobotInterface {
  private implicit val ec: ExecutionContext = system.executionContext
  private val random = new scala.util.Random(7)

  /** Everything asked of the stub, in order: "acquire 7 walk", "walk 7 0.1 0.0 0.2", ... */
  val calls = new ConcurrentLinkedQueue[String]()

  /** Robot 14 answers only once this is completed: later than any endpoint timeout a test sets. */
  val robot14Answers: Promise[Unit] = Promise[Unit]()

  /** How often a vision stream was started, and how often one ended. */
  val visionStarted = new AtomicInteger
  val visionEnded = new AtomicInteger

  val snapshot: RobotSnapshot = RobotSnapshot(
    7,
    new InetSocketAddress("127.0.0.1", 3838),
    teamId = Some(1),
    role = Some("striker"),
    posture = Some(Posture.Stand),
    batteryVoltage = Some(12.3),
    uptimeMillis = Some(5000L),
    online = true,
    quality = LinkQuality.Good
  )

  private def failure(robotId: Int, operation: String): Option[Throwable] = robotId match {
    case 99 => Some(RobotFailure.UnknownRobot(99))
    case 8  => Some(RobotFailure.RobotOffline(8))
    case 10 => Some(RobotFailure.RuleGate(naogateway.gateway.robot.Outbox.NoSendingWhileGameRuns))
    case 11 => Some(RobotFailure.Timeout(11, s"motion.$operation", 2000))
    case 12 => Some(RobotFailure.RobotError(12, "not standing: sit"))
    case 13 => Some(RobotFailure.SafetyHold(13, "battery low: 10.70 V (below 10.80 V)"))
    case _  => None
  }

  /** A result after a short random delay, so that answers overtake each other. */
  private def answer[T](robotId: Int, operation: String, value: => T): Future[T] = {
    calls.add(s"$operation $robotId")
    failure(robotId, operation) match {
      case Some(e)               => Future.failed(e)
      case None if robotId == 14 => robot14Answers.future.map(_ => value)
      case None => akka.pattern.after(random.synchronized(random.nextInt(15)).millis)(Future.successful(value))(system)
    }
  }

  def appName: String = "stub"

  def robots(): Future[Vector[RobotSnapshot]] =
    Future.successful(Vector(snapshot, snapshot.copy(robotId = 8, online = false, quality = LinkQuality.Offline)))

  def acquire(robotId: Int, groups: ActuatorGroup*): Future[Done] = {
    calls.add(s"acquire $robotId ${groups.map(_.name).mkString(",")}")
    robotId match {
      case 99 => Future.failed(RobotFailure.UnknownRobot(99))
      case 9  => Future.failed(RobotFailure.LeaseNotHeld(9, groups.head, Some("referee")))
      case _  => Future.successful(Done)
    }
  }

  def release(robotId: Int, groups: ActuatorGroup*): Unit = {
    calls.add(s"release $robotId ${groups.map(_.name).mkString(",")}"); ()
  }

  def walk(robotId: Int, vx: Double, vy: Double, omega: Double): Future[Done] =
    answer(robotId, f"walk $vx%.1f $vy%.1f $omega%.1f", Done)
  def stop(robotId: Int): Future[Done] = answer(robotId, "stop", Done)
  def head(robotId: Int, pan: Double, tilt: Double): Future[Done] = answer(robotId, f"head $pan%.1f $tilt%.1f", Done)
  def arms(robotId: Int, ls: Double, le: Double, rs: Double, re: Double): Future[Done] = answer(robotId, "arms", Done)
  def posture(robotId: Int, target: Posture.Target): Future[Posture] =
    answer(robotId, s"posture ${target.name}", target)
  def say(robotId: Int, text: String): Future[Done] = answer(robotId, s"say $text", Done)
  // Robot 7 has just sat down: its getPosture says so before its keep-alive (the snapshot's `stand`) does.
  def call(robotId: Int, module: String, method: String, params: RpcValue*): Future[Option[RpcValue]] =
    if (robotId == 7 && module == "motion" && method == "getPosture")
      answer(robotId, s"call $module.$method", Some(RpcValue.Text("sit")))
    else
      answer(robotId, s"call $module.$method",
        Some(RpcValue.Text(s"$robotId:$module.$method(${params.mkString(",")})")))

  def send(robotId: Int, operation: Operation): Future[Done] = {
    calls.add(s"send ${operation.name} $robotId")
    failure(robotId, operation.name).fold(Future.successful(Done): Future[Done])(Future.failed)
  }
  def status(robotId: Int): Source[RobotSnapshot, NotUsed] = allStatus.filter(_.robotId == robotId)
  def allStatus: Source[RobotSnapshot, NotUsed] =
    Source.tick(0.millis, 50.millis, snapshot).mapMaterializedValue(_ => NotUsed)

  def vision(robotId: Int, grid: Boolean): Source[VisionFrame, NotUsed] =
    Source
      .tick(0.millis, 50.millis,
        VisionFrame.Regions(robotId, 5L, Some(1234L),
          Vector(HaViMoRegion(1, 1, 20, 200, 300, 12, 8, 17, 13))): VisionFrame)
      .watchTermination() { (_, done) =>
        visionStarted.incrementAndGet()
        done.onComplete(_ => visionEnded.incrementAndGet())
        NotUsed
      }

  def linkStats(robotId: Int): Source[LinkStats, NotUsed] = Source.empty
  def gameState: Source[GameControlData, NotUsed] =
    Source.tick(0.millis, 50.millis, StubRobots.game).mapMaterializedValue(_ => NotUsed)
  def robotEvents: Source[RobotEvent, NotUsed] = Source.empty
  def appEvents: Source[AppEvent, NotUsed] = Source.empty
  def holds(): Future[Vector[robotmiddleware.RobotHolds]] = Future.successful(Vector.empty)
  def close(): Unit = { calls.add("close"); () }

  /** The calls so far. */
  def seen: Vector[String] = calls.asScala.toVector
}

/** Test data of the stub. */
object StubRobots {

  /** A version-8 control packet: PLAYING, teams 12 (blue, 2 goals) and 7 (red, 1 goal). */
  val gamePacket: Array[Byte] = {
    val b = new Array[Byte](158)
    "RGme".getBytes("US-ASCII").copyToArray(b, 0)
    b(4) = 8; b(5) = 4; b(6) = 6; b(7) = 3; b(8) = 1; b(9) = 1
    b(12) = 0xff.toByte; b(13) = 0xff.toByte
    b(14) = 0x4b; b(15) = 0x02
    b(18) = 12; b(19) = 0; b(20) = 2
    b(88) = 7; b(89) = 1; b(90) = 1
    b
  }

  val game: GameControlData = GameControllerCodec.decodeControl(gamePacket).fold(e => sys.error(e.describe), identity)
}
