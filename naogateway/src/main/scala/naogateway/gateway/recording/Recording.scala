package naogateway.gateway.recording

import naogateway.api.ClockEstimate
import naogateway.api.recording.{RecordingSchema, RecordingStats}
import naogateway.gateway.tap.Tap

/** Puts a robot's own clock (a `Status.timestamp`, milliseconds) on the gateway's clock (its JVM's `System.nanoTime`,
  * as [[naogateway.api.ClockEstimate]] does); the recorder turns that into Unix time for a message's publish time.
  */
trait RobotTimeBase {

  /** The gateway time of robot `robotId`'s clock reading `robotMillis`, once the robot's clock is estimated. */
  def toGatewayNanos(robotId: Int, robotMillis: Long): Option[Long]
}

/** Robot time bases. */
object RobotTimeBase {

  /** No robot's clock is known: a `Status` message is published at the time the gateway received it. */
  val Unknown: RobotTimeBase = (_: Int, _: Long) => None
}

/** The robots' clock estimates (`RobotSnapshot.clock`) as the robot actors put them at every keep-alive, read by the
  * recorder's thread: one slot per robot id, set by its actor (any incarnation of it), empty while the robot has no
  * estimate. A slot holds an immutable [[naogateway.api.ClockEstimate]], so a keep-alive costs a volatile write and no
  * message.
  */
final class RobotClockEstimates extends RobotTimeBase {
  private val estimates = new java.util.concurrent.ConcurrentHashMap[Int, RobotClockEstimates.Slot]()

  /** Robot `robotId`'s slot, the same one for every call. */
  def slot(robotId: Int): RobotClockEstimates.Slot =
    estimates.computeIfAbsent(robotId, _ => new RobotClockEstimates.Slot)

  def toGatewayNanos(robotId: Int, robotMillis: Long): Option[Long] = estimates.get(robotId) match {
    case null => None
    case slot =>
      slot.get match {
        case null     => None
        case estimate => Some(estimate.toGatewayNanos(robotMillis))
      }
  }
}

/** Robot clock estimates. */
object RobotClockEstimates {

  /** One robot's latest estimate (null while it has none): written by its robot actor, read by the recorder. */
  final class Slot extends java.util.concurrent.atomic.AtomicReference[ClockEstimate] {

    /** The robot's estimate now. */
    def update(estimate: Option[ClockEstimate]): Unit = set(estimate.orNull)
  }
}

/** The recorder as the gateway holds it: it reads the gateway's tap ([[naogateway.gateway.tap.Tap]]) on a thread of its
  * own; the gateway only asks for its figures and closes it.
  */
trait Recording {

  /** Whether anything is recorded. */
  def enabled: Boolean

  /** The figures so far. */
  def stats: RecordingStats

  /** Writes what waits, closes the file and stops the writer; later entries are ignored. */
  def close(): Unit
}

/** Recording on and off. */
object Recording {

  /** Records nothing. */
  val Off: Recording = new Recording {
    def enabled: Boolean = false
    def stats: RecordingStats = RecordingStats.Off
    def close(): Unit = ()
  }

  /** A recorder of what `tap` publishes, writing to `settings.directory` on a thread named `threadName`, or [[Off]]
    * when not enabled (then it does not subscribe).
    */
  def apply(settings: RecordingSettings, threadName: String, tap: Tap,
      clock: RobotTimeBase = RobotTimeBase.Unknown): Recording =
    if (settings.enabled) new Recorder(settings, threadName, clock, tap) else Off

  /** Topics of a recording (docs/recording.md): [[RecordingSchema.Topics]] (api), which the live feed names too. */
  val Topics: RecordingSchema.Topics.type = RecordingSchema.Topics

  /** Robots per file that get decoded channels of their own ([[RecordingSchema.MaxRobotChannels]], api). */
  val MaxRobotChannels: Int = RecordingSchema.MaxRobotChannels

  /** The schema data of every channel ([[RecordingSchema.descriptorSet]], api). */
  def descriptorSet: Array[Byte] = RecordingSchema.descriptorSet
}
