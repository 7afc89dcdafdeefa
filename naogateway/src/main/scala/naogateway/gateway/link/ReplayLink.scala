package naogateway.gateway.link

import java.io.{BufferedInputStream, IOException}
import java.net.{InetAddress, InetSocketAddress}
import java.nio.file.{Files, Path}
import java.util.concurrent.atomic.AtomicLong
import java.util.concurrent.locks.LockSupport

import scala.jdk.CollectionConverters._
import scala.util.Using
import scala.util.control.NonFatal

import org.slf4j.LoggerFactory

import naogateway.proto.{RecordedDatagram, RecordedDirection, RecordedPort}
import naogateway.gateway.recording.{Mcap, McapReader, Recording}
import naogateway.api.ReplayProgress

/** A recording to play back instead of the sockets: its files, in order, at `speed` times the recorded pace.
  *
  * @param files
  *   MCAP files written by the gateway's recorder (docs/recording.md), played one after the other
  */
final case class Replay(files: Vector[Path], speed: Double) {
  require(files.nonEmpty, "a replay needs at least one file")
  require(speed > 0 && speed <= 1000, s"replay speed $speed must be in (0, 1000]")
}

/** Choosing what to replay. */
object Replay {

  /** `path` itself, or every `.mcap` file of the directory `path` by name (the recorder's names sort by time). */
  def of(path: Path, speed: Double = 1.0): Replay = {
    val files =
      if (Files.isDirectory(path))
        Using.resource(Files.list(path))(
          _.iterator().asScala.filter(_.getFileName.toString.endsWith(".mcap")).toVector.sortBy(_.getFileName.toString))
      else Vector(path)
    require(files.nonEmpty, s"$path holds no .mcap file")
    files.foreach(f => require(Files.isRegularFile(f), s"recording $f does not exist"))
    Replay(files, speed)
  }
}

/** The gateway's robot link played back from a recording: the datagrams the gateway received on its robot port and on
  * its GameController port are handed to the gateway's usual handler at their recorded times (scaled by the speed), on
  * a thread of its own, as the robot port's reader hands live ones. Nothing is sent anywhere: what the gateway sends is
  * discarded and counted. When the recording ends the link stays open and quiet (the robots go offline as their
  * keep-alives stop).
  */
final class ReplayLink(replay: Replay, threadName: String) extends RobotLink {
  private val log = LoggerFactory.getLogger(classOf[ReplayLink])
  private val fed = new AtomicLong
  private val discarded = new AtomicLong
  @volatile private var open = true
  @volatile private var done = false
  @volatile private var thread: Option[Thread] = None

  /** No socket: the loopback address, port 0. */
  val localAddress: InetSocketAddress = new InetSocketAddress(InetAddress.getLoopbackAddress, 0)

  /** Discards the datagram (counted); it counts as sent. */
  def send(bytes: Array[Byte], to: InetSocketAddress): Boolean = {
    discarded.incrementAndGet()
    true
  }

  /** The figures so far. */
  def progress: ReplayProgress = ReplayProgress(fed.get, discarded.get, done)

  def start(handler: RobotPort.Handler): Unit = synchronized {
    require(thread.isEmpty, "the replay runs already")
    val t = new Thread(() => play(handler), threadName)
    t.setDaemon(true)
    thread = Some(t)
    t.start()
  }

  def close(joinMillis: Long): Unit = {
    open = false
    thread.foreach { t =>
      LockSupport.unpark(t)
      if (t ne Thread.currentThread()) t.join(joinMillis)
    }
  }

  private def play(handler: RobotPort.Handler): Unit = {
    val wallStart = System.nanoTime()
    var firstTime = Long.MinValue
    try {
      replay.files.iterator.takeWhile(_ => open).foreach { file =>
        log.info("Replaying {} at {}x", file, replay.speed)
        try Using.resource(new BufferedInputStream(Files.newInputStream(file), 256 * 1024)) { in =>
            val stream = McapReader.stream(in)
            var datagramChannels = Set.empty[Int]
            stream.items.takeWhile(_ => open).foreach {
              case McapReader.ChannelItem(c) if c.topic == Recording.Topics.Datagrams => datagramChannels += c.id
              case McapReader.MessageItem(m) if datagramChannels(m.channelId) =>
                if (firstTime == Long.MinValue) firstTime = m.logTime
                waitUntil(wallStart + ((m.logTime - firstTime) / replay.speed).toLong, handler)
                if (open) feed(RecordedDatagram.parseFrom(m.data), handler)
              case _ => ()
            }
          }
        catch {
          // A file cut short (the gateway did not stop cleanly) is played as far as it goes.
          case e @ (_: IOException | _: Mcap.FormatException) => log.warn(s"Replay of $file ended early: $e")
        }
      }
      log.info("Replay finished: {} datagrams handed to the gateway, {} outbound datagrams discarded", fed.get,
        discarded.get)
    } catch { case NonFatal(e) => log.error("Replay failed", e) }
    finally done = true
  }

  private def waitUntil(deadline: Long, handler: RobotPort.Handler): Unit = {
    var left = deadline - System.nanoTime()
    if (left > 0) handler.caughtUp()
    while (open && left > 0) {
      LockSupport.parkNanos(left)
      left = deadline - System.nanoTime()
    }
  }

  private def feed(d: RecordedDatagram, handler: RobotPort.Handler): Unit =
    if (d.direction == RecordedDirection.RECEIVED) {
      val from = address(d.source)
      val bytes = d.payload.toByteArray
      d.port match {
        case RecordedPort.ROBOT_PORT =>
          fed.incrementAndGet()
          handler.received(bytes, from)
        case RecordedPort.GAME_CONTROLLER =>
          fed.incrementAndGet()
          handler.gameControllerReceived(bytes, from)
        case _ => ()
      }
    }

  private def address(text: String): InetSocketAddress = {
    val colon = text.lastIndexOf(':')
    // A literal address: no name lookup.
    new InetSocketAddress(InetAddress.getByName(text.substring(0, colon)), text.substring(colon + 1).toInt)
  }
}
