package naogateway.sim.gs1500m

import scala.collection.immutable.ArraySeq

import naogateway.wire.{MessageContents, RobotReport}
import naogateway.sim.SeededRandom

/** A packet the CM-530 application hands to its send path; `encode` charges the protobuf encoding cost first. */
final case class Outgoing(cid: Int, data: ArraySeq[Byte], encode: Boolean = false, keepAlive: Boolean = false)

/** The firmware's periodic keep-alive (docs/protocol.md §2 and 6.2: a 24-byte `Status` every 200 ms). */
final case class KeepAlive(periodMillis: Double = 200.0, cid: Int = 0, payload: ArraySeq[Byte] = KeepAlive.StatusFrame)

/** The default keep-alive frame. */
object KeepAlive {

  /** A legacy-header FU-Remote `Status` of robot 1, team 1, of the thesis's keep-alive size (24 bytes). The thesis
    * gives only the size; timestamp 200 ms and 0 s online are chosen to make the size right.
    */
  val StatusFrame: ArraySeq[Byte] =
    MessageContents
      .encodeFrame(MessageContents(robotId = 1,
          status = Some(RobotReport(teamId = Some(1), uptimeMillis = Some(200L)).status)))
      .fold(_ => ArraySeq.fill[Byte](24)(0), ArraySeq.unsafeWrapArray(_))
}

/** Timing of the CM-530 firmware's main loop; every figure in unscaled milliseconds, turned into simulated time by
  * `costs` (which holds the time scale).
  *
  * @param loopPeriodMillis
  *   the main loop starts at most this often; a longer iteration starts the next one at once
  * @param pollMillis
  *   one serial poll besides moving the bytes (table 4: 0.01 ms)
  * @param messageHeaderMillis
  *   reading one WLAN message header (table 4: 0.05 ms)
  * @param handleMessageMillis
  *   handling one received datagram, fixed part (docs/simulator.md 1.4: parsing ≈ 5 ms)
  * @param handlePerByteMillis
  *   handling one received datagram, per payload byte (0 for protobuf messages; see [[OverflowExperiment]])
  * @param statusLineMillis
  *   reading one status line (table 4: up to 24.12 ms)
  * @param otherWorkMinMillis
  *   the rest of one loop iteration (motion, camera, …), drawn uniformly from [min, max] with the firmware's seed
  * @param otherWorkMaxMillis
  *   see `otherWorkMinMillis`
  * @param keepAlive
  *   the periodic keep-alive, if any
  */
final case class Cm530Config(
    costs: Cm530Costs = Cm530Costs.Real,
    loopPeriodMillis: Double = 10.0,
    pollMillis: Double = Cm530Costs.EmptyPollMillis,
    messageHeaderMillis: Double = Cm530Costs.MessageHeaderMillis,
    handleMessageMillis: Double = Cm530Costs.ParseMillis,
    handlePerByteMillis: Double = 0.0,
    statusLineMillis: Double = Cm530Costs.StatusLineMillis,
    otherWorkMinMillis: Double = 0.0,
    otherWorkMaxMillis: Double = 0.0,
    keepAlive: Option[KeepAlive] = Some(KeepAlive())
) {
  require(
    loopPeriodMillis >= 0.0 && otherWorkMinMillis >= 0.0 && otherWorkMaxMillis >= 0.0,
    "times must not be negative"
  )

  /** Unscaled milliseconds to handle one received datagram of `bytes` payload bytes. */
  def handleMillis(bytes: Int): Double = messageHeaderMillis + handleMessageMillis + handlePerByteMillis * bytes
}

/** What the firmware did, at simulated time `at`. */
sealed trait FirmwareEvent extends Product with Serializable {

  /** When (nanoseconds). */
  def at: Long
}

/** The firmware's observable actions. */
object FirmwareEvent {

  /** A datagram reached the application: its bytes were all read at `at`, and handling it ended at `handledAt`. */
  final case class Received(at: Long, handledAt: Long, cid: Int, remote: Option[Remote], bytes: ArraySeq[Byte])
      extends FirmwareEvent

  /** A status line from the module, read at `at` and parsed by `handledAt`. */
  final case class StatusReceived(at: Long, handledAt: Long, text: String) extends FirmwareEvent

  /** The firmware started pushing a packet to the module at `at`. */
  final case class Sent(at: Long, cid: Int, bytes: ArraySeq[Byte], keepAlive: Boolean) extends FirmwareEvent
}

/** Running totals of the firmware. */
final case class Cm530Stats(
    polls: Long = 0,
    bytesRead: Long = 0,
    received: Long = 0,
    statusLines: Long = 0,
    replies: Long = 0,
    garbageBytes: Long = 0,
    sends: Long = 0,
    keepAlives: Long = 0
)

/** The result of one firmware action: both next states, and what happened in each. */
final case class FirmwareStep(
    firmware: Cm530Firmware,
    module: Gs1500mModule,
    events: Vector[FirmwareEvent],
    moduleEvents: Vector[ModuleEvent]
)

/** A pure model of the CM-530 firmware's single-threaded main loop as the thesis describes it (no scheduler; every slow
  * task is polled): poll the module, handle what arrived, send what is due (keep-alive, queued packets), do the rest of
  * the robot's work, wait for the next period.
  *
  * The model is stepwise so that a driver can interleave it with the module's other inputs in time order: each [[act]]
  * performs exactly one interaction with the module, at [[nextActionAt]], and charges the CPU time that follows it; in
  * between, the module goes on receiving. [[ReceivePath.run]] is such a driver.
  *
  * The firmware's CPU time while reading equals the serial line time of the bytes read (it reads until the input is
  * empty), then each datagram costs [[Cm530Config.handleMillis]] and each status line [[Cm530Config.statusLineMillis]];
  * replies and garbage cost nothing beyond their bytes.
  */
final case class Cm530Firmware(
    config: Cm530Config,
    decoder: SerialDecoder,
    nextActionAt: Long,
    sendsNext: Boolean,
    loopStartedAt: Long,
    nextKeepAliveAt: Long,
    outbox: Vector[Outgoing],
    random: SeededRandom,
    stats: Cm530Stats
) {
  import FirmwareEvent._

  private def ns(millis: Double): Long = config.costs.nanos(millis)

  /** Queues a packet for the send phase of the current or next loop iteration. */
  def send(packet: Outgoing): Cm530Firmware = copy(outbox = outbox :+ packet)

  /** Performs the next action at [[nextActionAt]] against `module`. */
  def act(module: Gs1500mModule): FirmwareStep =
    if (sendsNext && outbox.nonEmpty) sendOne(module) else poll(module)

  private def poll(module: Gs1500mModule): FirmwareStep = {
    val read = module.firmwareRead(nextActionAt)
    val (nextDecoder, serialEvents) =
      if (read.bytes.isEmpty) (decoder, Vector.empty[SerialEvent]) else decoder.feed(read.bytes)
    var busy = read.doneAt + ns(config.pollMillis)
    var s = stats.copy(polls = stats.polls + 1, bytesRead = stats.bytesRead + read.bytes.length)
    val events = Vector.newBuilder[FirmwareEvent]
    serialEvents.foreach {
      case SerialEvent.Data(cid, remote, bytes) =>
        busy += ns(config.handleMillis(bytes.length))
        s = s.copy(received = s.received + 1)
        events += Received(read.doneAt, busy, cid, remote, bytes)
      case SerialEvent.StatusLine(text) =>
        busy += ns(config.statusLineMillis)
        s = s.copy(statusLines = s.statusLines + 1)
        events += StatusReceived(read.doneAt, busy, text)
      case _: SerialEvent.Reply   => s = s.copy(replies = s.replies + 1)
      case SerialEvent.Garbage(n) => s = s.copy(garbageBytes = s.garbageBytes + n)
    }
    val withKeepAlive = config.keepAlive match {
      case Some(k) if busy >= nextKeepAliveAt =>
        copy(
          outbox = Outgoing(k.cid, k.payload, encode = true, keepAlive = true) +: outbox,
          // A fixed schedule keeps the average rate at one per period; only a stall of a whole period resets it.
          nextKeepAliveAt =
            if (busy - nextKeepAliveAt >= ns(k.periodMillis)) busy + ns(k.periodMillis)
            else nextKeepAliveAt + ns(k.periodMillis)
        )
      case _ => this
    }
    val next = withKeepAlive.copy(decoder = nextDecoder, stats = s).continueAt(busy)
    FirmwareStep(next, read.module, events.result(), read.events)
  }

  private def sendOne(module: Gs1500mModule): FirmwareStep = {
    val packet = outbox.head
    val sendNanos = config.costs.serialSendNanos(packet.data.length)
    val step = module.firmwareSend(packet.cid, packet.data, nextActionAt, sendNanos)
    val s = stats.copy(
      sends = stats.sends + 1,
      keepAlives = stats.keepAlives + (if (packet.keepAlive) 1 else 0)
    )
    val next = copy(outbox = outbox.tail, stats = s).continueAt(nextActionAt + sendNanos)
    FirmwareStep(next, step.module, Vector(Sent(nextActionAt, packet.cid, packet.data, packet.keepAlive)), step.events)
  }

  // After a poll or a send, at `busy`: the next queued packet (after its encoding), or the rest of the loop.
  private def continueAt(busy: Long): Cm530Firmware =
    outbox.headOption match {
      case Some(packet) =>
        val encode = if (packet.encode) config.costs.encodeNanos(packet.data.length) else 0L
        copy(nextActionAt = busy + encode, sendsNext = true)
      case None =>
        val (work, nextRandom) = random.between(config.otherWorkMinMillis, config.otherWorkMaxMillis)
        // Strictly later than this action, so a driver always makes progress even when scaled times round to 0.
        val nextLoop =
          math.max(math.max(loopStartedAt + ns(config.loopPeriodMillis), busy + ns(work)), nextActionAt + 1)
        copy(nextActionAt = nextLoop, sendsNext = false, loopStartedAt = nextLoop, random = nextRandom)
    }
}

/** Where a firmware model starts. */
object Cm530Firmware {

  /** A firmware that polls first at `start`, its other work drawn with `seed`; its first keep-alive goes out in the
    * first loop iteration.
    */
  def apply(config: Cm530Config = Cm530Config(), seed: Long = 1L, start: Long = 0L): Cm530Firmware =
    Cm530Firmware(config, SerialDecoder.empty, start, sendsNext = false, start, start, Vector.empty,
      SeededRandom(seed), Cm530Stats())
}
