package naogateway.gateway.recording

import java.io.{BufferedOutputStream, IOException}
import java.net.InetSocketAddress
import java.nio.file.{Files, Path, StandardOpenOption}
import java.time.{Instant, ZoneOffset}
import java.time.format.DateTimeFormatter
import java.util.concurrent.atomic.AtomicLong
import java.util.concurrent.locks.LockSupport

import scala.collection.mutable
import scala.util.control.NonFatal

import org.slf4j.LoggerFactory

import naogateway.proto.RecordedPort
import naogateway.wire.RpcReply
import naogateway.api.recording.{Decision, DecisionJson, RecordEncoder, RecordingStats, Tapped}
import naogateway.gateway.tap.Tap

/** The recorder: a reader of the gateway's tap (a bounded queue that the gateway's threads only offer to), and one
  * writer thread of its own that drains it into MCAP files (decoding robot messages on the way, off the hot paths),
  * rotating them by size and age. A full queue drops the entry and counts it ([[RecordingStats.dropped]]). A file that
  * cannot be written is closed; entries are dropped (counted as failed) until a new file can be opened, tried every 5
  * s.
  */
final class Recorder(settings: RecordingSettings, threadName: String, clock: RobotTimeBase, tap: Tap)
    extends Recording {
  import Recording._

  private val log = LoggerFactory.getLogger(classOf[Recorder])
  private val queue = tap.subscribe("recorder", settings.queueCapacity)
  private val failedCount = new AtomicLong
  private val messageCount = new AtomicLong
  private val fileCount = new AtomicLong
  @volatile private var current: Option[String] = None
  private val retention = new RetentionKeeper(settings.directory, settings.retention)
  @volatile private var running = true
  // Wall-clock time of a nanoTime: one anchor, so times within a run never go backwards.
  private val epochAnchor = System.currentTimeMillis() * 1000000L
  private val nanoAnchor = System.nanoTime()
  private val thread = new Thread(() => writeLoop(), threadName)
  thread.setDaemon(true)

  def enabled: Boolean = true

  def stats: RecordingStats =
    RecordingStats(enabled = true, fileCount.get, messageCount.get, queue.stats.dropped, failedCount.get, current,
      Some(retention.status))

  def close(): Unit = {
    running = false
    LockSupport.unpark(thread)
    if (thread ne Thread.currentThread()) thread.join(5000)
  }

  private def epochNanos(nanoTime: Long): Long = epochAnchor + (nanoTime - nanoAnchor)

  // ------------------------------------------------------------------------------------------- the writer thread

  private var file: Option[FileWriter] = None
  // One file per half of a game (GameFiles), when recording.game-files is on.
  private var games = GameFiles(settings.gameQuiet.toNanos)
  private var nextAttempt = Long.MinValue
  private val batch = new java.util.ArrayList[Tapped](Recorder.Batch)
  // The writer's pause after a batch, to gather the next (Recorder.nextPark), and the entries waiting that end it.
  private var park = Recorder.MinParkNanos
  private val gather = math.max(1, math.min(Recorder.Batch / 4, settings.queueCapacity / 4))

  private def writeLoop(): Unit = {
    try {
      var closing = false
      while (!closing || queue.pending > 0) {
        // Asked to stop: off the tap first (nothing more comes), then what waits is written.
        if (!running && !closing) { queue.close(); closing = true }
        batch.clear()
        queue.drainTo(batch, Recorder.Batch)
        val now = System.nanoTime()
        file.foreach(f => if (f.due(now)) rotate() else if (f.flushDue(now)) flush(f, now))
        if (settings.gameFiles && gameSteps(games.tick(now))) rotate()
        if (batch.isEmpty) {
          // Nothing waits: the first entry offered wakes this thread (one wake-up, not one per entry), or the time
          // passes after which a flush, a rotation or a game file's end may be due.
          if (!closing) queue.await(Recorder.IdleWaitNanos)
        } else {
          var i = 0
          while (i < batch.size) { write(batch.get(i)); i += 1 }
          publishWritten()
          // A pause to gather the next entries: longer while they trickle in, so a busy writer wakes a bounded number
          // of times a second; ended early by a quarter batch waiting (a burst); none after a full batch (more wait
          // already).
          park = Recorder.nextPark(park, batch.size)
          if (!closing && batch.size < Recorder.Batch) queue.await(park, gather)
        }
      }
    } catch { case NonFatal(e) => log.error("Recording stopped: the writer failed", e) }
    finally { queue.close(); finish() }
  }

  // Messages written since the last batch ended: told to the figures once per batch, not once per message.
  private var written = 0L

  private def publishWritten(): Unit = if (written > 0) {
    messageCount.addAndGet(written)
    written = 0L
  }

  private def finish(): Unit = {
    publishWritten()
    file.foreach(f => closeQuietly(f))
    file = None
    current = None
  }

  private def rotate(): Unit = {
    file.foreach(closeQuietly)
    file = None
    current = None
  }

  private val FlushNanos = 1000000000L

  private def flush(f: FileWriter, now: Long): Unit = {
    f.flushedAt = now
    try f.writer.flush()
    catch { case ex: IOException => writeFailed(f, ex) }
  }

  /** A write to `f` failed (disk full, directory gone): counted, the file given up, a new one tried after a pause. */
  private def writeFailed(f: FileWriter, ex: IOException): Unit = {
    failedCount.incrementAndGet()
    log.error(s"Recording: writing ${f.path} failed; a new file in 5 s", ex)
    closeQuietly(f)
    file = None
    current = None
    nextAttempt = System.nanoTime() + RetryNanos
  }

  private val RetryNanos = 5000000000L

  private def closeQuietly(f: FileWriter): Unit =
    try f.close()
    catch { case e: IOException => log.error(s"Recording: could not close ${f.path}", e) }

  /** Takes the plan's next state; true when it has steps (each logged), i.e. the current file is to be closed. */
  private def gameSteps(next: (GameFiles, Vector[GameFiles.Step])): Boolean = {
    games = next._1
    next._2.foreach(step =>
      log.info("Recording: {}",
        step match { case GameFiles.Begin(h) => s"${h.label} begins"; case GameFiles.End(why) => why }))
    next._2.nonEmpty
  }

  private def write(e: Tapped): Unit = {
    // A half begins with the packet that begins it in its file; it ends with the packet that ends it still in it.
    val endAfter = e match {
      case Tapped.Decided(at, Decision.Published(naogateway.api.GameStateUpdated(data))) if settings.gameFiles =>
        val steps = games.packet(data, at)
        if (gameSteps(steps) && steps._2.exists(_.isInstanceOf[GameFiles.Begin])) { rotate(); false }
        else steps._2.nonEmpty
      case _ => false
    }
    writeEntry(e)
    if (endAfter) rotate()
  }

  private def writeEntry(e: Tapped): Unit = {
    if (file.isEmpty && System.nanoTime() >= nextAttempt) open()
    file match {
      case Some(f) =>
        try {
          val before = f.writer.messages
          f.write(e)
          written += f.writer.messages - before
          if (f.writer.size >= settings.rotateBytes) rotate()
        } catch { case ex: IOException => writeFailed(f, ex) }
      case None =>
        failedCount.incrementAndGet()
    }
  }

  private def open(): Unit = {
    val name = GameFiles.fileName(FileTime.format(Instant.now()), games.half, fileCount.get + 1)
    val path = settings.directory.resolve(name)
    try {
      Files.createDirectories(settings.directory)
      val out =
        new BufferedOutputStream(Files.newOutputStream(path, StandardOpenOption.CREATE_NEW, StandardOpenOption.WRITE),
          256 * 1024)
      file = Some(new FileWriter(path, new McapWriter(out, "", "naogateway recording"), System.nanoTime()))
      fileCount.incrementAndGet()
      current = Some(path.toString)
      log.info("Recording to {}", path)
      retention.sweep(Set(path))
    } catch {
      case e: IOException =>
        log.error(s"Recording: cannot open $path; trying again in 5 s", e)
        nextAttempt = System.nanoTime() + RetryNanos
    }
  }

  private val FileTime = DateTimeFormatter.ofPattern("yyyyMMdd-HHmmss").withZone(ZoneOffset.UTC)

  // Last in the constructor: the writer thread reads the fields above.
  thread.start()

  /** One open file with its channels. */
  private final class FileWriter(val path: Path, val writer: McapWriter, openedAt: Long) {
    private val schema = writer.addSchema("naogateway.proto.RecordedDatagram", "protobuf", descriptorSet)
    private val datagrams = writer.addChannel(Topics.Datagrams, "protobuf", schema)
    private val decisions = writer.addChannel(Topics.Decisions, "json", 0)
    private val statusSchema = writer.addSchema("naogateway.proto.Status", "protobuf", descriptorSet)
    private val healthSchema = writer.addSchema("naogateway.proto.RobotHealth", "protobuf", descriptorSet)
    private val messageSchema = writer.addSchema("naogateway.proto.Message", "protobuf", descriptorSet)
    private val servosSchema = writer.addSchema("naogateway.proto.ServoTelemetry", "protobuf", descriptorSet)
    // Per robot id: its status, health, message and servos channels, made when first needed; at most MaxRobotChannels
    // robots.
    private val robots = mutable.LongMap.empty[Array[Int]]
    private val encoder = new RecordEncoder

    def due(now: Long): Boolean = now - openedAt >= settings.rotateInterval.toNanos

    // A crash loses at most the last second: the chunk being filled is written out at least once a second.
    var flushedAt: Long = openedAt
    def flushDue(now: Long): Boolean = now - flushedAt >= FlushNanos

    def close(): Unit = writer.close()

    /** Robot `robotId`'s status, health, message and servos channels; null when the file has no room for another robot.
      */
    private def robotChannels(robotId: Int): Array[Int] = {
      val known = robots.getOrNull(robotId.toLong)
      if ((known ne null) || robots.size >= MaxRobotChannels) known
      else {
        val ids = Array(
          writer.addChannel(Topics.status(robotId), "protobuf", statusSchema, Map("robotID" -> robotId.toString)),
          writer.addChannel(Topics.health(robotId), "protobuf", healthSchema, Map("robotID" -> robotId.toString)),
          writer.addChannel(Topics.message(robotId), "protobuf", messageSchema, Map("robotID" -> robotId.toString)),
          writer.addChannel(Topics.servos(robotId), "protobuf", servosSchema, Map("robotID" -> robotId.toString))
        )
        robots(robotId.toLong) = ids
        ids
      }
    }

    def write(e: Tapped): Unit = {
      val time = epochNanos(e.nanoTime)
      e match {
        case d: Tapped.Datagram =>
          val n = encoder.datagram(d, addressBytes(d.source), addressBytes(d.destination))
          writer.write(datagrams, time, time, encoder.bytes, 0, n)
          if (d.port == RecordedPort.ROBOT_PORT && d.received) decoded(d, time)
        case Tapped.Decided(_, decision) =>
          writer.write(decisions, time, time,
            DecisionJson.of(decision, time).getBytes(java.nio.charset.StandardCharsets.UTF_8))
      }
    }

    /** A robot's frame on its decoded channels, and a reply as a decision of its own: only a frame the port's reader
      * accepted and decoded (`Tapped.Datagram.decoded`); anything else is kept raw, on `/gateway/datagrams`.
      */
    private def decoded(d: Tapped.Datagram, time: Long): Unit =
      d.decoded match {
        case Some(c) =>
          val ids = robotChannels(c.robotId)
          if (ids ne null) {
            c.status.foreach { s =>
              // The robot's own time of the keep-alive, on the gateway's clock once the robot's clock is estimated.
              val robotTime = s.timestamp.orElse(c.robotHealth.flatMap(_.uptimeMs).map(_.toLong & 0xffffffffL))
              val published = robotTime.flatMap(t => clock.toGatewayNanos(c.robotId, t)).map(epochNanos).getOrElse(time)
              writer.write(ids(0), time, published, encoder.bytes, 0, encoder.message(s))
            }
            c.robotHealth.foreach(h => writer.write(ids(1), time, time, encoder.bytes, 0, encoder.message(h)))
            c.servoTelemetry.foreach(t => writer.write(ids(3), time, time, encoder.bytes, 0, encoder.message(t)))
            // Anything beyond a keep-alive's status, health and servo telemetry goes on the message channel, whole.
            if (RecordEncoder.onMessageChannel(c)) writer.write(ids(2), time, time, c.toProtobuf)
          }
          c.rpcResponse.foreach { r =>
            writer.write(decisions, time, time,
              DecisionJson.reply(c.robotId, RpcReply.fromProto(r), time).getBytes(
                java.nio.charset.StandardCharsets.UTF_8))
          }
        case None => () // kept raw; the gateway counted the refusal
      }
  }

  // The UTF-8 bytes of `address` for the addresses met lately (writer thread only): a robot sends from the same
  // address again and again. Emptied when full, so a flood of addresses costs no more memory than MaxAddresses.
  // IPv4 addresses (all the gateway meets in practice) are keyed by address and port in one Long; others by the
  // socket address itself.
  private val ipv4Addresses = mutable.LongMap.empty[Array[Byte]]
  private val otherAddresses = new java.util.HashMap[InetSocketAddress, Array[Byte]]()
  private val MaxAddresses = 4096
  private def addressBytes(a: InetSocketAddress): Array[Byte] =
    if (a == null) RecordEncoder.addressBytes(a)
    else
      a.getAddress match {
        case ip: java.net.Inet4Address =>
          // An Inet4Address's hash code is its 32-bit address.
          val key = (ip.hashCode.toLong & 0xffffffffL) << 16 | a.getPort.toLong
          val known = ipv4Addresses.getOrNull(key)
          if (known ne null) known
          else {
            if (ipv4Addresses.size >= MaxAddresses) ipv4Addresses.clear()
            val bytes = addressText(a)
            ipv4Addresses(key) = bytes
            bytes
          }
        case _ =>
          val known = otherAddresses.get(a)
          if (known ne null) known
          else {
            if (otherAddresses.size >= MaxAddresses) otherAddresses.clear()
            val bytes = addressText(a)
            otherAddresses.put(a, bytes)
            bytes
          }
      }

  private def addressText(a: InetSocketAddress): Array[Byte] = RecordEncoder.addressBytes(a)
}

/** The writer's pace. */
private[recording] object Recorder {

  /** The most entries taken from the queue at once. */
  val Batch: Int = 1024

  /** The shortest pause after a batch, while entries arrive in numbers. */
  val MinParkNanos: Long = 2000000L

  /** The longest pause after a batch, while entries trickle in (an idle field's keep-alives): the writer then wakes 4
    * times a second. A burst does not wait it out: a quarter batch waiting wakes the writer (`Tap.Reader.await`), so
    * the queue (65536 entries by default) never fills while the writer sleeps.
    */
  val MaxParkNanos: Long = 250000000L

  /** How long the writer waits on an empty queue when no entry comes: the flush (at least once a second), rotation and
    * the end of a game's half are looked at when it wakes.
    */
  val IdleWaitNanos: Long = 1000000000L

  /** The pause after a batch of `drained` entries: back to [[MinParkNanos]] for a quarter of a full batch or more
    * (traffic picked up), else doubled up to [[MaxParkNanos]].
    */
  def nextPark(park: Long, drained: Int): Long =
    if (drained >= Batch / 4) MinParkNanos
    else math.min(park * 2, MaxParkNanos)
}
