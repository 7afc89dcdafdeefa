package naogateway.recording

import java.net.InetSocketAddress

import scala.collection.mutable

import com.google.protobuf.DescriptorProtos.FileDescriptorSet
import com.google.protobuf.Descriptors.FileDescriptor

import naogateway._
import naogateway.proto.{DebuggingProto, HavimoProto, MessageProto, RecordedPort, RecordingProto, RpcProto}

/**
 * Puts a robot's own clock (a `Status.timestamp`, milliseconds) on the gateway's clock (its JVM's `System.nanoTime`,
 * as [[naogateway.ClockEstimate]] does); the recorder turns that into Unix time for a message's publish time.
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

/**
 * The robots' clock estimates as the robot actors last published them (`RobotSnapshot.clock`), read by the recorder's
 * thread: one entry per robot actor, replaced at every keep-alive, removed while a robot has no estimate.
 */
final class RobotClockEstimates extends RobotTimeBase {
  private val estimates = new java.util.concurrent.ConcurrentHashMap[Int, ClockEstimate]()

  /** Robot `robotId`'s estimate now. */
  def update(robotId: Int, estimate: Option[ClockEstimate]): Unit = estimate match {
    case Some(e) => estimates.put(robotId, e)
    case None    => estimates.remove(robotId)
  }

  def toGatewayNanos(robotId: Int, robotMillis: Long): Option[Long] =
    Option(estimates.get(robotId)).map(_.toGatewayNanos(robotMillis))
}

/** A gateway decision worth recording, handed over as data and written as JSON by the writer thread. */
sealed trait Decision extends Product with Serializable

/** The decisions. */
object Decision {

  /** A robot or game event the gateway published (online, offline, restarted, link quality, game state). */
  final case class Published(event: GatewayEvent) extends Decision

  /** What the outbox did with one datagram for robot `robotId`: `sent`, `queued`, `refused-by-rule`, `dropped`. */
  final case class Outgoing(robotId: Int, priority: Priority, outcome: String, bytes: Array[Byte]) extends Decision

  /** The competition gate opened or closed on `reading` (a game state, or a packet that could not be read). */
  final case class Gate(open: Boolean, reading: naogateway.GameReading) extends Decision

  /** The team budget's state: bytes each way over the last second, the limit, the queues. */
  final case class Budget(outBytes: Long, inBytes: Long, limit: Int, queued: Map[String, Int]) extends Decision
}

/**
 * Where the gateway hands what it records. Every method is thread-safe, returns at once and never blocks: the port's
 * reader thread and the outbox call it on their hot paths.
 */
trait Recording {

  /** Whether anything is recorded. */
  def enabled: Boolean

  /** A datagram that passed `port`, `received` or sent, byte for byte; `robotId` the robot at the far end (-1: none). */
  def datagram(port: RecordedPort, received: Boolean, source: InetSocketAddress, destination: InetSocketAddress, bytes: Array[Byte],
      robotId: Int): Unit

  /** A decision of the gateway. */
  def decision(decision: Decision): Unit

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
    def datagram(port: RecordedPort, received: Boolean, source: InetSocketAddress, destination: InetSocketAddress, bytes: Array[Byte],
        robotId: Int): Unit = ()
    def decision(decision: Decision): Unit = ()
    def stats: RecordingStats = RecordingStats.Off
    def close(): Unit = ()
  }

  /** A recorder writing to `settings.directory` on a thread named `threadName`, or [[Off]] when not enabled. */
  def apply(settings: RecordingSettings, threadName: String, clock: RobotTimeBase = RobotTimeBase.Unknown): Recording =
    if (settings.enabled) new Recorder(settings, threadName, clock) else Off

  /** Topics of a recording (docs/recording.md). */
  object Topics {
    val Datagrams: String = "/gateway/datagrams"
    val Decisions: String = "/gateway/decisions"
    def status(robotId: Int): String = s"/robot/$robotId/status"
    def health(robotId: Int): String = s"/robot/$robotId/health"
    def message(robotId: Int): String = s"/robot/$robotId/message"
  }

  /** Robots per file that get decoded channels of their own; datagrams of further robot ids are kept raw only. */
  val MaxRobotChannels: Int = 64

  /** Every .proto file of the project with its imports, dependencies first: the schema data of every channel. */
  lazy val descriptorSet: Array[Byte] = {
    val ordered = mutable.LinkedHashMap.empty[String, FileDescriptor]
    def add(f: FileDescriptor): Unit = if (!ordered.contains(f.getName)) {
      f.getDependencies.forEach(d => add(d))
      ordered(f.getName) = f
    }
    Seq(MessageProto.javaDescriptor, DebuggingProto.javaDescriptor, HavimoProto.javaDescriptor, RpcProto.javaDescriptor,
      RecordingProto.javaDescriptor).foreach(add)
    val set = FileDescriptorSet.newBuilder()
    ordered.values.foreach(f => set.addFile(f.toProto))
    set.build().toByteArray
  }
}
