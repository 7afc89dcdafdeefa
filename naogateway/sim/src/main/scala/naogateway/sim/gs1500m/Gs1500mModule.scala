package naogateway.sim.gs1500m

import scala.collection.immutable.ArraySeq
import naogateway.sim.SeededRandom

/** A pure model of the robot's GainSpan GS1500M WiFi module in bulk data mode, as the thesis observed it (§6.1).
  *
  * '''One shared buffer.''' Incoming and outgoing payload share [[Gs1500mConfig.bufferBytes]] (1400) bytes. Only
  * payload counts: the module keeps each datagram's serial header with it as bookkeeping, so a 1400-byte datagram fits
  * an empty buffer, as the module's 1400-byte datagram limit requires. Replies and status lines come from the module's
  * command processor and take no data buffer.
  *
  * '''The serial line is the bottleneck.''' The radio moves data far faster than 46080 bytes/s (thesis §6.1: a PC sends
  * several MB/s, and "the serial interface for reading the buffer is not fast enough to empty it"), so the model gives
  * the radio no time at all: an arriving datagram is in the buffer at once, and an outgoing packet goes on air the
  * moment its last byte has crossed the serial line. Outgoing payload is reserved in full when the CM-530 starts
  * sending it and freed when it goes on air; that errs towards a fuller buffer by at most one packet's transfer time.
  *
  * '''The CM-530 reads only when it polls.''' Incoming data stay in the module until [[firmwareRead]]; a read takes
  * everything queued at that instant over the line at the line rate (the thesis's `recvWlanData` reads until the input
  * is empty), freeing its buffer space evenly while it crosses. Bytes arriving during a read wait for the next.
  *
  * '''Overflow.''' When a datagram does not fit into the free space, a seeded coin decides: with probability
  * [[Gs1500mConfig.overwriteProbability]] the module behaves like an overrunning ring buffer and writes the new
  * datagram over the oldest unread bytes, so the oldest queued datagram(s) lose their beginning (and with it the
  * receive header; the CM-530 then reads a headerless tail, the thesis's "incomplete receive header"); otherwise, and
  * whenever the unread bytes could not make enough room (bytes already crossing the line cannot be taken back), the new
  * datagram is lost. An outgoing packet that does not fit overwrites unread incoming data the same way (the serial
  * input has no flow control), or is lost if even that is not enough.
  *
  * Every input takes the current simulated time in nanoseconds; time never runs backwards (an earlier time is taken as
  * the module's clock).
  */
final case class Gs1500mModule(
    config: Gs1500mConfig,
    clock: Long,
    rxQueue: Vector[RxEntry],
    drains: Vector[Drain],
    tx: Vector[TxEntry],
    rxLineFreeAt: Long,
    txLineFreeAt: Long,
    random: SeededRandom,
    nextId: Long,
    stats: Gs1500mStats
) {
  import ModuleEvent._

  /** Payload bytes queued for the CM-530 and not yet being read. */
  def queuedBytes: Int = {
    var sum = 0
    rxQueue.foreach(e => sum += e.bufferBytes)
    sum
  }

  /** Bytes of the buffer in use at `t` (at or after [[clock]]). */
  def bufferedAt(t: Long): Int = {
    var sum = queuedBytes
    drains.foreach(d => sum += d.remainingAt(t))
    tx.foreach(e => if (e.endsAt > t) sum += e.data.length)
    sum
  }

  /** Bytes of the buffer in use now. */
  def buffered: Int = bufferedAt(clock)

  /** Free buffer bytes now. */
  def free: Int = config.bufferBytes - buffered

  /** When the next outgoing packet goes on air, if one is on the line (a driver may [[advance]] to it). */
  def nextOnAirAt: Option[Long] = tx.headOption.map(_.endsAt)

  /** Lets time pass to `now`: outgoing packets whose transfer is complete go on air (and are acknowledged). */
  def advance(now: Long): ModuleStep = {
    val t = math.max(now, clock)
    if (!tx.exists(_.endsAt <= t)) {
      // Nothing goes on air: only the clock moves on (and finished reads let go of their buffer space).
      val left = if (drains.exists(_.endsAt <= t)) drains.filter(_.endsAt > t) else drains
      ModuleStep(if (t == clock && (left eq drains)) this else copy(clock = t, drains = left), Vector.empty)
    } else {
      val (done, pending) = tx.partition(_.endsAt <= t)
      val replies: Vector[RxEntry] =
        if (config.acknowledgeSends) done.map(_ => RxEntry.ReplyEntry(SerialEvent.Ack)) else Vector.empty
      val next = copy(
        clock = t,
        tx = pending,
        drains = drains.filter(_.endsAt > t),
        rxQueue = rxQueue ++ replies,
        stats = stats.copy(
          onAir = stats.onAir + done.size,
          bytesOnAir = stats.bytesOnAir + done.iterator.map(_.data.length.toLong).sum
        )
      )
      ModuleStep(next, done.map(e => OnAir(e.cid, e.data, e.endsAt)))
    }
  }

  /** A datagram reaches the module from the air at `now`. */
  def arrive(datagram: AirDatagram, now: Long): ModuleStep = {
    val ModuleStep(m, early) = advance(now)
    val t = m.clock
    val id = m.nextId
    val length = datagram.payload.length
    val counted = m.copy(nextId = id + 1, stats = m.stats.copy(arrived = m.stats.arrived + 1))
    def lose(reason: LossReason, random: SeededRandom) = {
      val c = counted.stats
      val c2 =
        if (reason == LossReason.Oversize) c.copy(lost = c.lost + 1, lostOversize = c.lostOversize + 1)
        else c.copy(lost = c.lost + 1)
      ModuleStep(counted.copy(random = random, stats = c2), early :+ Lost(id, t, reason))
    }
    if (length > config.bufferBytes || length > Gs1500mSerial.MaxPayload) lose(LossReason.Oversize, m.random)
    else
      Gs1500mSerial.headerBytes(datagram.cid, datagram.remote, length) match {
        case Left(error) =>
          val c = counted.stats
          ModuleStep(counted.copy(stats = c.copy(refused = c.refused + 1)), early :+ Refused(error.describe, t))
        case Right(header) =>
          val frame = RxEntry.Frame(id, datagram, header, t, 0)
          val deficit = length - (config.bufferBytes - m.bufferedAt(t))
          if (deficit <= 0) counted.enqueue(frame, early, Vector.empty)
          else {
            val (coin, random) = m.random.nextDouble
            if (coin < config.overwriteProbability && m.queuedBytes >= deficit) {
              val (queue, overwrites, newly) = overwrite(m.rxQueue, deficit, t)
              val c = counted.stats
              counted
                .copy(
                  rxQueue = queue,
                  random = random,
                  stats = c.copy(
                    overwritten = c.overwritten + newly,
                    overwrittenBytes = c.overwrittenBytes + deficit
                  )
                )
                .enqueue(frame, early, overwrites)
            } else lose(LossReason.BufferFull, random)
          }
      }
  }

  /** The CM-530 polls the serial port at `now` and reads everything queued; the bytes have all arrived at `doneAt`. */
  def firmwareRead(now: Long): ReadStep = {
    val ModuleStep(m, early) = advance(now)
    val t = m.clock
    if (m.rxQueue.isEmpty) ReadStep(m, Gs1500mModule.NoBytes, t, early)
    else {
      val out = new Array[Byte](m.rxQueue.foldLeft(0)(_ + _.serialLength))
      m.rxQueue.foldLeft(0)((at, e) => e.copySerialBytes(out, at))
      val bytes = ArraySeq.unsafeWrapArray(out)
      val start = math.max(t, m.rxLineFreeAt)
      val end = start + config.lineNanos(bytes.length)
      val frames = m.rxQueue.collect { case f: RxEntry.Frame => f }
      val intact = frames.count(_.overwritten == 0)
      val c = m.stats
      val next = m.copy(
        rxQueue = Vector.empty,
        drains = if (m.queuedBytes > 0) m.drains :+ Drain(m.queuedBytes, start, end) else m.drains,
        rxLineFreeAt = end,
        stats = c.copy(
          readIntact = c.readIntact + intact,
          readDamaged = c.readDamaged + (frames.size - intact),
          bytesToFirmware = c.bytesToFirmware + bytes.length
        )
      )
      val reads = frames.map(f => ReadOut(f.id, end, f.overwritten == 0))
      ReadStep(next, bytes, end, (early ++ reads) :+ ToFirmware(bytes, start, end))
    }
  }

  /** The CM-530 starts handing `data` for connection `cid` to the module at `now`, as `ESC 'Z'` bulk data.
    *
    * `transferNanos` is how long the CM-530 takes to push the frame out (its measured send cost is about eleven times
    * the line time); the packet goes on air when that or the line time, whichever is longer, has passed after the line
    * is free.
    */
  def firmwareSend(cid: Int, data: ArraySeq[Byte], now: Long, transferNanos: Long = 0L): ModuleStep = {
    val ModuleStep(m, early) = advance(now)
    val t = m.clock
    val c = m.stats.copy(sends = m.stats.sends + 1)
    Gs1500mSerial.bulkHeader(cid, data.length) match {
      case Right(header) if data.length <= config.bufferBytes =>
        val start = math.max(t, m.txLineFreeAt)
        val end = start + math.max(config.lineNanos(header.length + data.length), transferNanos)
        val entry = TxEntry(cid, data, start, end)
        val deficit = data.length - (config.bufferBytes - m.bufferedAt(t))
        if (deficit <= 0) m.copy(tx = m.tx :+ entry, txLineFreeAt = end, stats = c).withPeak(early)
        else if (m.queuedBytes >= deficit) {
          val (queue, overwrites, newly) = overwrite(m.rxQueue, deficit, t)
          m.copy(
            rxQueue = queue,
            tx = m.tx :+ entry,
            txLineFreeAt = end,
            stats = c.copy(overwritten = c.overwritten + newly, overwrittenBytes = c.overwrittenBytes + deficit)
          ).withPeak(early ++ overwrites)
        } else {
          // The module acknowledges the loss as soon as it gives up; the bytes still occupy the line.
          val fail: Vector[RxEntry] =
            if (config.acknowledgeSends) Vector(RxEntry.ReplyEntry(SerialEvent.Fail)) else Vector.empty
          ModuleStep(
            m.copy(rxQueue = m.rxQueue ++ fail, txLineFreeAt = end, stats = c.copy(sendsLost = c.sendsLost + 1)),
            early :+ SendLost(cid, data.length, t)
          )
        }
      case Right(_) =>
        val refused = Refused(s"${data.length} bytes exceed the buffer", t)
        ModuleStep(m.copy(stats = c.copy(refused = c.refused + 1)), early :+ refused)
      case Left(error) =>
        ModuleStep(m.copy(stats = c.copy(refused = c.refused + 1)), early :+ Refused(error.describe, t))
    }
  }

  /** The module writes a text status line (e.g. `DISCONNECT 0`) for the CM-530 at `now`. */
  def statusLine(text: String, now: Long): ModuleStep = {
    val ModuleStep(m, early) = advance(now)
    Gs1500mSerial.encode(SerialEvent.StatusLine(text)) match {
      case Right(bytes) => ModuleStep(m.copy(rxQueue = m.rxQueue :+ RxEntry.StatusEntry(text, bytes)), early)
      case Left(error) =>
        val c = m.stats
        ModuleStep(m.copy(stats = c.copy(refused = c.refused + 1)), early :+ Refused(error.describe, m.clock))
    }
  }

  private def enqueue(frame: RxEntry.Frame, early: Vector[ModuleEvent], overwrites: Vector[ModuleEvent]): ModuleStep =
    copy(rxQueue = rxQueue :+ frame, stats = stats.copy(buffered = stats.buffered + 1))
      .withPeak(early ++ overwrites :+ Buffered(frame.id, frame.arrivedAt, frame.datagram.payload.length))

  private def withPeak(events: Vector[ModuleEvent]): ModuleStep =
    ModuleStep(copy(stats = stats.copy(peakBuffered = math.max(stats.peakBuffered, buffered))), events)

  // Overwrites `deficit` bytes from the front of the unread queue, oldest first; returns the new queue, the events
  // and how many datagrams lost their beginning for the first time.
  private def overwrite(queue: Vector[RxEntry], deficit: Int, at: Long): (Vector[RxEntry], Vector[ModuleEvent], Int) = {
    var left = deficit
    var newly = 0
    val kept = Vector.newBuilder[RxEntry]
    val events = Vector.newBuilder[ModuleEvent]
    queue.foreach {
      case f: RxEntry.Frame if left > 0 && f.remaining > 0 =>
        val k = math.min(left, f.remaining)
        left -= k
        if (f.overwritten == 0) newly += 1
        val g = f.copy(overwritten = f.overwritten + k)
        events += Overwritten(f.id, at, k, g.remaining)
        if (g.remaining > 0) kept += g
      case other => kept += other
    }
    (kept.result(), events.result(), newly)
  }
}

/** Where a module model starts. */
object Gs1500mModule {

  // An empty read, wrapping a byte array as every read does (ArraySeq.empty would wrap an Object array).
  private val NoBytes: ArraySeq[Byte] = ArraySeq.unsafeWrapArray(Array.emptyByteArray)

  /** An empty module at time `start`, its overflow coin seeded with `seed`. */
  def apply(config: Gs1500mConfig = Gs1500mConfig(), seed: Long = 1L, start: Long = 0L): Gs1500mModule =
    Gs1500mModule(config, start, Vector.empty, Vector.empty, Vector.empty, start, start, SeededRandom(seed), 0L,
      Gs1500mStats())
}
