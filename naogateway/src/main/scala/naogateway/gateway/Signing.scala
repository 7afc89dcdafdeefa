package naogateway.gateway

import java.time.Instant
import java.util.concurrent.ConcurrentHashMap
import java.util.concurrent.atomic.{AtomicLong, AtomicReference}

import scala.annotation.tailrec

import naogateway.wire._

/** Whether the gateway requires a robot's frames to be signed (docs/protocol.md 6.7; `robots[].signing`). */
sealed abstract class RobotSigning(val name: String) extends Product with Serializable

/** The two signing settings of a robot. */
object RobotSigning {

  /** Signatures are neither required nor produced; a signed frame is accepted, its signature skipped. */
  case object Off extends RobotSigning("off")

  /** Only frames that verify and pass the replay window count; everything sent to the robot is signed. The default of
    * every robot while a team key is set.
    */
  case object Required extends RobotSigning("required")

  /** Every setting. */
  val all: Vector[RobotSigning] = Vector(Off, Required)

  /** A robot's setting when its config entry names none, or when it is discovered: `required` with a team key. */
  def defaultFor(teamKey: Option[SigningKey]): RobotSigning = if (teamKey.isDefined) Required else Off

  /** The setting named `text` (`off` or `required`). */
  def parse(text: String): Either[String, RobotSigning] =
    all.find(_.name == text.trim).toRight(s"signing is ${all.map(_.name).mkString(" or ")}, not '${text.trim}'")
}

/** The gateway's check of one robot's signed frames: the robot's key and its replay window, which lives here and
  * nowhere else; the window's last timestamp carries the robot's boot epoch, which the gateway's frames to it are
  * signed under. The gateway keeps one per robot id for its whole run ([[GatewaySigning]]), so it outlives restarts of
  * the robot actor and re-discoveries. Every frame for that robot passes it before anything acts on the frame: on the
  * robot port's reader, or in the gateway for the frames the reader leaves to it, hence the window is an atomic value.
  */
final class SignatureCheck private[naogateway] (val robotId: Int, key: RobotKey) {
  private val window = new AtomicReference(ReplayWindow.empty)
  private val link = SignedLink.FromRobot(robotId)

  /** `Right` when `frame` (whose header decoded as `header`) is signed by this robot and newer than every frame of it
    * accepted before.
    */
  def check(frame: Array[Byte], header: FrameHeader): Either[Rejection, Unit] =
    verify(frame, header).flatMap(accept)

  /** The signature alone, without touching the window: its timestamp when it verifies. */
  private[naogateway] def verify(frame: Array[Byte], header: FrameHeader): Either[Rejection, Long] =
    FrameSigning.verifyFrame(frame, header, key, link).left.map(Rejection.of).map(_.timestamp)

  /** The last timestamp accepted, if any. */
  def lastAccepted: Option[Long] = window.get.last

  /** The robot's boot epoch: the high 32 bits of its last accepted timestamp; unknown before its first signed frame. */
  def epoch: Option[Int] = lastAccepted.map(FrameSigning.epochOf)

  /** `frame` (encoded, unsigned, not gzip-flagged) signed for this robot in its current epoch under `timestamp`. */
  private[naogateway] def sign(frame: Array[Byte], timestamp: Long): Either[SignRefusal, Array[Byte]] =
    epoch match {
      case None => Left(SignRefusal.EpochUnknown(robotId))
      case Some(e) =>
        FrameSigning.signEncoded(frame, key, SignedLink.ToRobot(robotId, e), timestamp).left.map(SignRefusal.Unsignable)
    }

  @tailrec private[naogateway] final def accept(timestamp: Long): Either[Rejection, Unit] = {
    val now = window.get
    now.accept(timestamp) match {
      case Left(error) => Left(Rejection.of(error))
      case Right(next) => if (window.compareAndSet(now, next)) Right(()) else accept(timestamp)
    }
  }

  override def toString: String = s"SignatureCheck($robotId)"
}

/** Why the gateway did not sign a frame to a robot: it is then dropped and counted, never sent unsigned. */
sealed abstract class SignRefusal(val describe: String) extends Product with Serializable

/** The reasons a frame is not signed. */
object SignRefusal {

  /** No signed frame of the robot was accepted in this run, so its boot epoch (part of the MAC) is unknown. */
  final case class EpochUnknown(robotId: Int)
      extends SignRefusal(s"robot $robotId's boot epoch is not known yet (no signed frame of it accepted in this run)")

  /** The frame cannot be signed as it is (not a frame, or gzip-flagged). */
  final case class Unsignable(error: FrameError) extends SignRefusal(s"the frame cannot be signed: ${error.describe}")
}

/** The gateway's signing (docs/protocol.md 6.7): the team key, each robot's [[SignatureCheck]] under its derived key,
  * and the gateway's timestamps. Frames to robots are signed at the moment they leave (the outbox), so the timestamps
  * grow in the order the robots receive them: signed earlier but sent later (a lower priority class waiting for the
  * budget), a frame would fall below the robot's replay window. Timestamps are microseconds since the Unix epoch,
  * always above the last one used, one sequence for all robots; the gateway keeps one of these for its run.
  */
final class GatewaySigning(team: SigningKey, nowMicros: () => Long = GatewaySigning.epochMicros) {
  private val robots = new ConcurrentHashMap[Int, SignatureCheck]
  private val last = new AtomicLong(0L)
  private val refused = new AtomicLong(0L)

  /** Robot `robotId`'s check, created at its first use: for configured robots at the start, for others once a frame of
    * theirs verified ([[checkNew]]), so invented robot ids keep nothing here.
    */
  def robot(robotId: Int): SignatureCheck =
    robots.computeIfAbsent(robotId, id => new SignatureCheck(id, team.robotKey(id)))

  /** Checks a frame of a robot that has no check yet (not configured, not discovered): the check is kept only when the
    * frame's signature verifies and passes the window.
    */
  def checkNew(robotId: Int, frame: Array[Byte], header: FrameHeader): Either[Rejection, SignatureCheck] =
    Option(robots.get(robotId)) match {
      case Some(known) => known.check(frame, header).map(_ => known)
      case None =>
        val fresh = new SignatureCheck(robotId, team.robotKey(robotId))
        fresh.verify(frame, header).flatMap { _ =>
          val kept = robots.computeIfAbsent(robotId, _ => fresh)
          kept.check(frame, header).map(_ => kept)
        }
    }

  /** Robot `robotId`'s boot epoch as the gateway knows it. */
  def epochOf(robotId: Int): Option[Int] = Option(robots.get(robotId)).flatMap(_.epoch)

  /** Whether a frame to `robotId` can be signed now (its boot epoch is known). */
  def canSign(robotId: Int): Boolean = epochOf(robotId).isDefined

  /** `frame` (encoded, unsigned, not gzip-flagged) to robot `robotId`, signed under the next gateway timestamp. */
  def sign(robotId: Int, frame: Array[Byte]): Either[SignRefusal, Array[Byte]] = {
    val signed = Option(robots.get(robotId)).toRight(SignRefusal.EpochUnknown(robotId)).flatMap { check =>
      if (check.epoch.isEmpty) Left(SignRefusal.EpochUnknown(robotId))
      else check.sign(frame, last.updateAndGet(l => FrameSigning.nextGatewayTimestamp(l, nowMicros())))
    }
    if (signed.isLeft) refused.incrementAndGet()
    signed
  }

  /** Frames not signed (and so not sent) so far. */
  def refusals: Long = refused.get

  override def toString: String = "GatewaySigning"
}

/** The gateway's clock for signatures. */
object GatewaySigning {

  /** Microseconds since the Unix epoch, from the system clock. */
  val epochMicros: () => Long = () => {
    val now = Instant.now()
    now.getEpochSecond * 1000000L + now.getNano / 1000
  }
}
