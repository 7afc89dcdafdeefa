package naogateway

import java.time.Instant
import java.util.concurrent.atomic.{AtomicLong, AtomicReference}

import scala.annotation.tailrec

import naogateway.wire._

/** Whether the gateway requires a robot's frames to be signed (docs/protocol.md 6.7; `robots[].signing`). */
sealed abstract class RobotSigning(val name: String) extends Product with Serializable

/** The two signing settings of a robot. */
object RobotSigning {

  /** Signatures are neither required nor produced; a signed frame is accepted, its signature skipped (the default). */
  case object Off extends RobotSigning("off")

  /** Only frames that verify and pass the replay window count; everything sent to the robot is signed. */
  case object Required extends RobotSigning("required")

  /** Every setting. */
  val all: Vector[RobotSigning] = Vector(Off, Required)

  /** The setting named `text` (`off` or `required`). */
  def parse(text: String): Either[String, RobotSigning] =
    all.find(_.name == text.trim).toRight(s"signing is ${all.map(_.name).mkString(" or ")}, not '${text.trim}'")
}

/** The gateway's check of one robot's signed frames: the team key and the robot's replay window, which lives here and
  * nowhere else. The gateway creates one per robot with `signing = required` and keeps it with the robot's route, so it
  * outlives restarts of the robot actor. Every frame for that robot passes it before anything acts on the frame: on the
  * robot port's reader, or in the gateway for the frames the reader leaves to it (a re-bind), hence the window is an
  * atomic value.
  */
final class SignatureCheck(key: SigningKey) {
  private val window = new AtomicReference(ReplayWindow.empty)

  /** `Right` when `frame` (whose header decoded as `header`) is signed by the robot and newer than every frame accepted
    * before.
    */
  def check(frame: Array[Byte], header: FrameHeader): Either[Rejection, Unit] =
    FrameSigning.verifyFrame(frame, header, key, SignDirection.RobotToGateway) match {
      case Left(error)   => Left(Rejection.of(error))
      case Right(signed) => accept(signed.timestamp)
    }

  /** The last timestamp accepted, if any (for tests and figures). */
  def lastAccepted: Option[Long] = window.get.last

  @tailrec private def accept(timestamp: Long): Either[Rejection, Unit] = {
    val now = window.get
    now.accept(timestamp) match {
      case Left(error) => Left(Rejection.of(error))
      case Right(next) => if (window.compareAndSet(now, next)) Right(()) else accept(timestamp)
    }
  }

  override def toString: String = "SignatureCheck"
}

/** Signs frames to robots at the moment they leave (the outbox), so the gateway's timestamps grow in the order the
  * robot receives them: signed earlier but sent later (a lower priority class waiting for the budget), a frame would
  * fall below the robot's replay window. Timestamps are microseconds since the Unix epoch, always above the last one
  * used (docs/protocol.md 6.7); the gateway keeps one signer, so a restarted outbox continues where it was.
  */
final class FrameSigner(key: SigningKey, nowMicros: () => Long = FrameSigner.epochMicros) {
  private val last = new AtomicLong(0L)

  /** `frame` (encoded, unsigned, not gzip-flagged) with its signature, under the next gateway timestamp. */
  def sign(frame: Array[Byte]): Either[FrameError, Array[Byte]] = {
    val timestamp = last.updateAndGet(l => FrameSigning.nextGatewayTimestamp(l, nowMicros()))
    FrameSigning.signEncoded(frame, key, SignDirection.GatewayToRobot, timestamp)
  }

  override def toString: String = "FrameSigner"
}

/** The gateway's clock for signatures. */
object FrameSigner {

  /** Microseconds since the Unix epoch, from the system clock. */
  val epochMicros: () => Long = () => {
    val now = Instant.now()
    now.getEpochSecond * 1000000L + now.getNano / 1000
  }
}
