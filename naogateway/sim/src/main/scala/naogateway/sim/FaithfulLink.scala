package naogateway.sim

import java.net.{Inet4Address, InetAddress, InetSocketAddress}

import scala.collection.immutable.{ArraySeq, Queue}
import scala.collection.mutable.ArrayBuffer

import naogateway.sim.gs1500m.{
  Cm530Config,
  Cm530Costs,
  Cm530Firmware,
  FirmwareEvent,
  FirmwareStep,
  Gs1500mConfig,
  Gs1500mModule,
  ModuleEvent,
  Remote
}

/** A simulated robot's WiFi path through the GS1500M module model and the CM-530 main loop model, as a pure value in
  * the robot's clock (nanoseconds); [[SimulatedRobot]] drives it with `faithfulLink = true`.
  *
  * Inbound, a datagram from the air enters the module's shared 1400-byte buffer at once (or is lost, or overwrites
  * unread data), waits there until the CM-530 polls, crosses the serial line framed as `ESC 'y'` (the robot is a UDP
  * server on port 3838), is decoded by [[SerialDecoder]], and reaches the application when the firmware has finished
  * handling it ([[FaithfulLink.Delivery.at]]). Outbound, the application hands a frame to the CM-530, which encodes it
  * (encoding cost), pushes it to the module as `ESC 'Z'` bulk data (serial send cost), and the module puts it on air
  * when its last byte has crossed the line; until then it holds buffer space shared with inbound data.
  *
  * The CM-530's idle main-loop iterations (polls that find nothing) are skipped rather than simulated: when work
  * appears while the loop is idle, the next poll is the first loop tick at or after that moment, exactly when the
  * modelled loop would have found it. So an idle robot costs nothing, and a driver needs a wake-up only at
  * [[nextWakeUp]].
  *
  * Every input takes the current time; time never runs backwards (an earlier time is taken as the latest one seen).
  * Build one with the companion's `apply(module, cpu, timeScale, seed, now)`.
  */
final case class FaithfulLink(
    module: Gs1500mModule,
    cpu: Cm530Firmware,
    // Destinations of the frames in `cpu.outbox`, in the same order.
    queued: Queue[InetSocketAddress],
    // Destinations of the frames the module holds for sending, in the order they go on air.
    onLine: Queue[InetSocketAddress],
    // Received datagrams whose handling has not yet finished, by completion time.
    handling: Queue[FaithfulLink.Delivery]
) {
  import FaithfulLink._

  /** The next moment [[advance]] has something to show, if any: a frame goes on air or the application gets a datagram.
    * The steps in between (the CM-530's polls, encodings and sends) need no wake-up of their own: `advance` runs them
    * in time order whenever it is called, and nothing outside sees them happen.
    */
  def nextWakeUp: Option[Long] = {
    val q = quiet
    if (q.visibleAt == Long.MaxValue) None else Some(q.visibleAt)
  }

  /** The next moment [[advance]] has anything to do, if any, a step nobody sees included. */
  def nextStepAt: Option[Long] = {
    val next = math.min(nextEventAt, handling.headOption.fold(Long.MaxValue)(_.at))
    if (next == Long.MaxValue) None else Some(next)
  }

  /** A datagram from `from` reaches the module at `now`. */
  def arrive(bytes: Array[Byte], from: InetSocketAddress, now: Long): Step = {
    val caughtUp = advance(now)
    val t = math.max(now, caughtUp.link.module.clock)
    val remote = remoteOf(from)
    val datagram = gs1500m.AirDatagram(ServerCid, remote, ArraySeq.unsafeWrapArray(bytes))
    val step = caughtUp.link.module.arrive(datagram, t)
    caughtUp.copy(link = caughtUp.link.copy(module = step.module).wake(t))
  }

  /** The application hands `frame` for `to` to the CM-530's send path at `now`. */
  def send(frame: Array[Byte], to: InetSocketAddress, now: Long): Step = {
    val caughtUp = advance(now)
    val t = math.max(now, caughtUp.link.module.clock)
    val l = caughtUp.link
    val packet = gs1500m.Outgoing(ServerCid, ArraySeq.unsafeWrapArray(frame), encode = true)
    caughtUp.copy(link = l.copy(cpu = l.cpu.send(packet), queued = l.queued.enqueue(to)).wake(t))
  }

  /** Lets the module and the CM-530 run up to `now`, in time order: what went on air, and what the application got. */
  def advance(now: Long): Step = {
    // The steps a quiet run already took are the first steps of this run whenever `now` reaches them; it is used only
    // when [[nextWakeUp]] has made it, as a driver does before it waits.
    val q = quietRun
    if (q == null || now < q.through) advanceFrom(now, Vector.empty)
    else if (now >= q.visibleAt && q.shown != null) q.shown.advanceFrom(now, q.shownTransmitted)
    else q.link.advanceFrom(now, Vector.empty)
  }

  // Runs every step up to `now` from this link, in time order, after steps that put `already` on air.
  private def advanceFrom(now: Long, already: Vector[Transmission]): Step = {
    var link = this
    val transmitted = new ArrayBuffer[Transmission]
    transmitted ++= already
    var events = 0
    while (events < MaxEventsPerStep && link.nextEventAt <= now) {
      events += 1
      link = link.stepOnce(transmitted)
    }
    val sent = if (transmitted.isEmpty) Vector.empty else transmitted.toVector
    val h = link.handling
    if (h.isEmpty || h.head.at > now) Step(link, sent, Vector.empty)
    else {
      val (due, later) = h.span(_.at <= now)
      Step(link.copy(handling = later), sent, due.toVector)
    }
  }

  // When the next step is due: the CM-530's next action while it has work, or the next packet going on air.
  private def nextEventAt: Long = {
    val cpuAt = if (cpuHasWork) cpu.nextActionAt else Long.MaxValue
    math.min(cpuAt, onAirAt)
  }

  // When the next packet goes on air (Long.MaxValue: none on the line).
  private def onAirAt: Long = if (module.tx.isEmpty) Long.MaxValue else module.tx.head.endsAt

  // The one next step; a packet on air first when it is strictly earlier than the CM-530's action.
  private def stepOnce(transmitted: ArrayBuffer[Transmission]): FaithfulLink = {
    val cpuAt = if (cpuHasWork) cpu.nextActionAt else Long.MaxValue
    val airAt = onAirAt
    if (airAt < cpuAt) {
      val step = module.advance(airAt)
      copy(module = step.module).onModuleEvents(step.events, transmitted, sent = false).wake(airAt)
    } else {
      val step = cpu.act(module)
      copy(cpu = step.firmware, module = step.module).onCpuStep(step, transmitted)
    }
  }

  // The link run without inputs through every step before its next visible one: a pure function of this value, made
  // once ([[nextWakeUp]] makes it, `advance` uses it when there). `through` is the time of the last step taken
  // (Long.MinValue for none), `visibleAt` when the first step that puts a frame on air, or the first delivery, is due
  // (Long.MaxValue for never); `shown` the link after that step when it put frames on air (`shownTransmitted`).
  @volatile private var quietRun: FaithfulLink.Quiet = null

  private def quiet: FaithfulLink.Quiet = {
    if (quietRun == null) quietRun = runQuietly
    quietRun
  }

  private def runQuietly: FaithfulLink.Quiet = {
    var link = this
    var through = Long.MinValue
    var visibleAt = Long.MaxValue
    var shown: FaithfulLink = null
    var shownTransmitted = Vector.empty[Transmission]
    var searching = true
    var events = 0
    val scratch = new ArrayBuffer[Transmission]
    while (searching) {
      val at = link.nextEventAt
      val deliveryAt = link.handling.headOption.fold(Long.MaxValue)(_.at)
      if (deliveryAt <= at || events >= MaxEventsPerStep) {
        visibleAt = math.min(deliveryAt, at)
        searching = false
      } else {
        events += 1
        val next = link.stepOnce(scratch)
        if (scratch.nonEmpty) {
          visibleAt = at
          shown = next
          shownTransmitted = scratch.toVector
          searching = false
        } else {
          link = next
          through = at
        }
      }
    }
    FaithfulLink.Quiet(link, through, visibleAt, shown, shownTransmitted)
  }

  private def cpuHasWork: Boolean = cpu.outbox.nonEmpty || module.rxQueue.nonEmpty

  // An idle loop would have polled at every tick; the first tick at or after `t` is when it notices new work.
  private def wake(t: Long): FaithfulLink =
    if (!cpuHasWork || cpu.nextActionAt >= t) this
    else {
      val period = cpu.config.costs.nanos(cpu.config.loopPeriodMillis)
      val tick =
        if (period <= 0 || cpu.loopStartedAt >= t) math.max(t, cpu.loopStartedAt)
        else cpu.loopStartedAt + (t - cpu.loopStartedAt + period - 1) / period * period
      copy(cpu = cpu.copy(nextActionAt = tick, loopStartedAt = tick, sendsNext = false))
    }

  private def onCpuStep(step: FirmwareStep, transmitted: ArrayBuffer[Transmission]): FaithfulLink = {
    var link = this
    var sent = false
    step.events.foreach {
      case FirmwareEvent.Sent(_, _, _, _) =>
        // The CM-530 sends the head of its outbox; its destination moves on with it.
        sent = true
        link.queued.dequeueOption.foreach { case (to, rest) =>
          link = link.copy(queued = rest, onLine = link.onLine.enqueue(to))
        }
      case FirmwareEvent.Received(_, handledAt, _, remote, bytes) =>
        link =
          link.copy(handling = link.handling.enqueue(Delivery(bytes.toArray, remote.flatMap(addressOf), handledAt)))
      case FirmwareEvent.StatusReceived(_, _, _) => ()
    }
    link.onModuleEvents(step.moduleEvents, transmitted, sent)
  }

  // `sent`: the events are those of handing a packet to the module, so a loss or refusal is about that packet, the
  // last one on the line (packets already on the line go on air first, in order).
  private def onModuleEvents(
      events: Vector[ModuleEvent],
      transmitted: ArrayBuffer[Transmission],
      sent: Boolean
  ): FaithfulLink = {
    if (events.isEmpty) this
    else {
      var onAir = onLine
      events.foreach {
        case ModuleEvent.OnAir(_, data, at) =>
          onAir.dequeueOption.foreach { case (to, rest) =>
            transmitted += Transmission(data.toArray, to, at)
            onAir = rest
          }
        case ModuleEvent.SendLost(_, _, _) | ModuleEvent.Refused(_, _) if sent && onAir.nonEmpty =>
          onAir = onAir.init
        case _ => ()
      }
      if (onAir eq onLine) this else copy(onLine = onAir)
    }
  }
}

/** Construction and outputs of [[FaithfulLink]]. */
object FaithfulLink {

  /** The module connection the robot uses for everything: its UDP server on port 3838. */
  val ServerCid: Int = 0

  /** Bounds the events one [[FaithfulLink.advance]] processes, so a wrong clock can never spin a driver forever. */
  val MaxEventsPerStep: Int = 100000

  /** A received datagram the firmware has finished handling at `at`; `from` is `None` when its header named no sender.
    */
  final case class Delivery(bytes: Array[Byte], from: Option[InetSocketAddress], at: Long)

  /** A datagram the module put on air at `at`. */
  final case class Transmission(bytes: Array[Byte], to: InetSocketAddress, at: Long)

  // A link run quietly up to its next visible step: see `FaithfulLink.quietRun`.
  private final case class Quiet(
      link: FaithfulLink,
      through: Long,
      visibleAt: Long,
      shown: FaithfulLink,
      shownTransmitted: Vector[Transmission]
  )

  /** The link after an input, what went on air and what the application got, both in time order. */
  final case class Step(link: FaithfulLink, transmitted: Vector[Transmission], delivered: Vector[Delivery])

  /** An empty module and an idle CM-530 loop at `now`; the CM-530's own keep-alive is off (the firmware sends its own).
    *
    * @param timeScale
    *   multiplies every modelled duration (serial line, encode, send, handling, loop period)
    */
  def apply(module: Gs1500mConfig, cpu: Cm530Config, timeScale: Double, seed: Long, now: Long): FaithfulLink =
    FaithfulLink(
      Gs1500mModule(module.copy(timeScale = timeScale), seed = seed, start = now),
      Cm530Firmware(cpu.copy(costs = Cm530Costs(timeScale), keepAlive = None), seed = SeededRandom(seed).split(7).state,
        start = now),
      Queue.empty,
      Queue.empty,
      Queue.empty
    )

  // The module reports a sender as a dotted IPv4 address; any other sender arrives framed without one (`ESC 'Z'`).
  private def remoteOf(address: InetSocketAddress): Option[Remote] =
    Option(address.getAddress).collect { case ip: Inet4Address => Remote(ip.getHostAddress, address.getPort) }

  // The ip in a Remote is a dotted literal, so no name lookup happens here.
  private def addressOf(remote: Remote): Option[InetSocketAddress] =
    scala.util.Try(new InetSocketAddress(InetAddress.getByName(remote.ip), remote.port)).toOption
}
