package naogateway.sim

import scala.collection.immutable.{ArraySeq, Queue}
import scala.concurrent.duration._

import naogateway.sim.gs1500m.{
  Cm530Firmware,
  Cm530Stats,
  FirmwareEvent,
  Gs1500mStats,
  Gs1500mModule,
  ModuleEvent,
  OverflowExperiment,
  Outgoing
}
import naogateway.wire.Datagram
import naogateway.wire.stream.{SecureStream, StreamStats, StreamSettings}

/** The thesis's overflow experiment (docs/simulator.md §6) over the secure stream, through the same GS1500M and CM-530
  * models as the raw run of [[OverflowExperiment]], in simulated time.
  *
  * The gateway side offers the 100 payloads of 1 kB to a gateway-side [[SecureStream]], one every 50 ms (byte 0 of
  * payload i, 0-based, is i, the rest is the raw run's random bytes). Its segments reach the module from the air and
  * wait in its 1400-byte buffer until the CM-530 reads them; the robot-side [[SecureStream]] takes each segment when
  * the firmware has finished handling it, and the robot sums byte 0 of every payload the stream delivers. The robot's
  * ACKs go into the CM-530's send queue, are pushed to the module in the send phase of the next loop iteration (sharing
  * the buffer with inbound data, with the serial send cost) and reach the gateway's stream when they go on air. The
  * firmware's 24-byte keep-alive competes for the module as in the raw run; the gateway ignores it here. The radio
  * takes `airLatency` each way (default none, as in the module model).
  *
  * Everything runs in one discrete-event loop over the pure pieces, so a configuration always gives the same run. On a
  * tie, an arrival is in the module before the firmware acts (as in [[gs1500m.ReceivePath]]). The run ends once the
  * robot has delivered every payload and the gateway has seen every one acknowledged, or at `timeLimit` of simulated
  * time, or after `maxEvents` events.
  *
  * With the defaults (the thesis firmware's window 1, sequence numbers 0..20, seed 1) the robot sums 4950: every
  * payload exactly once, in order, where the raw run sums 963. The stream pays in time, not in payloads: at window 1
  * each payload needs a round trip through the firmware's ≈ 230 ms of reading and handling.
  */
object StreamOverflowExperiment {

  /** The experiment's parameters.
    *
    * @param experiment
    *   the raw experiment's payloads, schedule, module, firmware and seed; its `timeScale` must be 1 because the
    *   stream's timers (RTO, idle ACK) are in real time
    * @param stream
    *   both endpoints' settings
    * @param airLatency
    *   the one-way radio delay in both directions
    * @param timeLimit
    *   simulated time after which the run stops unfinished
    * @param maxEvents
    *   a bound on processed events, so a run always stops
    */
  final case class Config(
      experiment: OverflowExperiment.Config = OverflowExperiment.Config(),
      stream: StreamSettings = StreamSettings.thesis,
      airLatency: FiniteDuration = Duration.Zero,
      timeLimit: FiniteDuration = 10.minutes,
      maxEvents: Long = 1000000L
  ) {
    require(experiment.timeScale == 1.0,
      s"the stream's timers are unscaled, so timeScale must be 1, was ${experiment.timeScale}")
    require(airLatency >= Duration.Zero, s"airLatency must not be negative, was $airLatency")
    require(timeLimit > Duration.Zero, s"timeLimit must be positive, was $timeLimit")
    require(maxEvents > 0L, s"maxEvents must be positive, was $maxEvents")
  }

  /** What the robot summed and what it cost.
    *
    * @param sent
    *   payloads the gateway offered
    * @param sum
    *   the robot's sum of byte 0 over every payload its stream delivered
    * @param expectedSum
    *   the right sum (4950 for 100 payloads)
    * @param delivered
    *   byte 0 of every delivered payload, in the order delivered
    * @param completed
    *   whether every payload was delivered and acknowledged before a limit struck
    * @param lastDeliveryAt
    *   simulated nanoseconds until the robot delivered its last payload (0 if none)
    * @param finishedAt
    *   simulated nanoseconds at which the run ended (all acknowledged, or a limit)
    * @param gateway
    *   the gateway-side endpoint's stats (retransmissions, timeouts, …)
    * @param robot
    *   the robot-side endpoint's stats (duplicates dropped, ACKs sent, …)
    * @param module
    *   the GS1500M's stats (losses, overwrites, peak buffer use)
    * @param cpu
    *   the CM-530 loop's stats
    * @param events
    *   events processed
    */
  final case class Result(
      sent: Int,
      sum: Long,
      expectedSum: Long,
      delivered: Vector[Int],
      completed: Boolean,
      lastDeliveryAt: Long,
      finishedAt: Long,
      gateway: StreamStats,
      robot: StreamStats,
      module: Gs1500mStats,
      cpu: Cm530Stats,
      events: Long
  ) {

    /** Simulated seconds until the robot had the last payload. */
    def seconds: Double = lastDeliveryAt / 1e9

    /** Data segments the gateway sent again. */
    def retransmissions: Long = gateway.retransmissions

    /** Whether the robot delivered payloads 0, 1, 2, … each exactly once and in order (byte 0 modulo 256). */
    def inOrder: Boolean = delivered == (0 until sent).map(_ & 0xff)
  }

  /** The raw run and the stream run of the same configuration. */
  final case class Comparison(raw: OverflowExperiment.Result, stream: Result)

  /** Both runs: the raw one of [[OverflowExperiment]] and the one through the stream. */
  def compare(config: Config = Config()): Comparison =
    Comparison(OverflowExperiment.run(config.experiment), run(config))

  /** Runs the payloads through the gateway's stream, the module, the CM-530 and the robot's stream. */
  def run(config: Config = Config()): Result = new Run(config).execute()

  // What can happen next, in the order ties are broken.
  private final val AppSend = 0
  private final val ToModule = 1
  private final val ToGateway = 2
  private final val OnAir = 3
  private final val Handled = 4
  private final val GatewayTimer = 5
  private final val RobotTimer = 6
  private final val FirmwareAct = 7
  private final val Kinds = 8

  private final class Run(config: Config) {
    private val ex = config.experiment
    private val payloads: Vector[Array[Byte]] = OverflowExperiment.datagrams(ex).map(_.payload.toArray)
    private val sendAt: Vector[Long] = payloads.indices.map(i => ex.nanos(i * ex.spacingMillis)).toVector
    private val latency = config.airLatency.toNanos
    private val timeLimit = config.timeLimit.toNanos

    private var gateway = SecureStream.initial(config.stream, 0L)
    private var robot = SecureStream.initial(config.stream, 0L)
    private var module = Gs1500mModule(ex.scaledModule, seed = ex.seed)
    private var firmware = Cm530Firmware(ex.scaledFirmware, seed = SeededRandom(ex.seed).split(7).state)
    // Both queues fill in time order with a fixed latency, so their heads are always the earliest.
    private var toModule = Queue.empty[(Long, Array[Byte])]
    private var toGateway = Queue.empty[(Long, Array[Byte])]
    // Datagrams the firmware has read, by the end of their handling; polls end in time order, so this is sorted.
    private var handling = Queue.empty[(Long, Array[Byte])]
    private var nextSend = 0
    private var gatewayTickedAt = Long.MinValue
    private var robotTickedAt = Long.MinValue
    private val delivered = Vector.newBuilder[Int]
    private var deliveredCount = 0
    private var acknowledged = 0
    private var lastDeliveryAt = 0L

    def execute(): Result = {
      var now = 0L
      var events = 0L
      val times = new Array[Long](Kinds)
      while (!done && events < config.maxEvents && now <= timeLimit) {
        times(AppSend) = if (nextSend < payloads.size) sendAt(nextSend) else Long.MaxValue
        times(ToModule) = toModule.headOption.fold(Long.MaxValue)(_._1)
        times(ToGateway) = toGateway.headOption.fold(Long.MaxValue)(_._1)
        times(OnAir) = module.nextOnAirAt.getOrElse(Long.MaxValue)
        times(Handled) = handling.headOption.fold(Long.MaxValue)(_._1)
        // A timer that asks for a moment already handled is served one nanosecond later, so time always moves on.
        times(GatewayTimer) = gateway.nextTimerAt.fold(Long.MaxValue)(t => math.max(t, gatewayTickedAt + 1))
        times(RobotTimer) = robot.nextTimerAt.fold(Long.MaxValue)(t => math.max(t, robotTickedAt + 1))
        times(FirmwareAct) = firmware.nextActionAt
        var kind = 0
        var k = 1
        while (k < Kinds) {
          if (times(k) < times(kind)) kind = k
          k += 1
        }
        now = math.max(now, times(kind))
        if (now <= timeLimit) {
          events += 1
          handle(kind, now)
        }
      }
      val got = delivered.result()
      Result(
        sent = payloads.size,
        sum = got.iterator.map(_.toLong).sum,
        expectedSum = payloads.iterator.filter(_.nonEmpty).map(p => (p(0) & 0xff).toLong).sum,
        delivered = got,
        completed = done,
        lastDeliveryAt = lastDeliveryAt,
        finishedAt = math.min(now, timeLimit),
        gateway = gateway.stats,
        robot = robot.stats,
        module = module.stats,
        cpu = firmware.stats,
        events = events
      )
    }

    private def done: Boolean = deliveredCount >= payloads.size && acknowledged >= payloads.size

    private def handle(kind: Int, now: Long): Unit = kind match {
      case AppSend =>
        val i = nextSend
        nextSend += 1
        // A refused payload never arrives, so the run ends unfinished and the result shows the gap.
        gateway.send(payloads(i), i.toLong, None, now).foreach(fromGateway(_, now))
      case ToModule =>
        val (arrival, rest) = toModule.dequeue
        toModule = rest
        val datagram = gs1500m.AirDatagram(ex.cid, Some(ex.peer), ArraySeq.unsafeWrapArray(arrival._2))
        val step = module.arrive(datagram, now)
        module = step.module
        onModule(step.events)
      case ToGateway =>
        val (arrival, rest) = toGateway.dequeue
        toGateway = rest
        // The robot's keep-alives reach the gateway too; only segments concern the stream.
        if (Datagram.isStreamSegment(arrival._2)) fromGateway(gateway.receive(arrival._2, now), now)
      case OnAir =>
        val step = module.advance(now)
        module = step.module
        onModule(step.events)
      case Handled =>
        val (read, rest) = handling.dequeue
        handling = rest
        if (Datagram.isStreamSegment(read._2)) fromRobot(robot.receive(read._2, now), now)
      case GatewayTimer =>
        gatewayTickedAt = now
        fromGateway(gateway.tick(now), now)
      case RobotTimer =>
        robotTickedAt = now
        fromRobot(robot.tick(now), now)
      case _ =>
        val step = firmware.act(module)
        firmware = step.firmware
        module = step.module
        step.events.foreach {
          case FirmwareEvent.Received(_, handledAt, _, _, bytes) =>
            handling = handling.enqueue(handledAt -> bytes.toArray)
          case FirmwareEvent.StatusReceived(_, _, _) | FirmwareEvent.Sent(_, _, _, _) => ()
        }
        onModule(step.moduleEvents)
    }

    private def onModule(events: Vector[ModuleEvent]): Unit =
      events.foreach {
        case ModuleEvent.OnAir(_, data, at) => toGateway = toGateway.enqueue((at + latency) -> data.toArray)
        case _                              => ()
      }

    private def fromGateway(step: SecureStream.Step, now: Long): Unit = {
      gateway = step.state
      step.outputs.foreach {
        case SecureStream.Transmit(d)                          => toModule = toModule.enqueue((now + latency) -> d)
        case SecureStream.Acknowledged(_)                      => acknowledged += 1
        case SecureStream.Deliver(_) | SecureStream.Expired(_) => ()
      }
    }

    private def fromRobot(step: SecureStream.Step, now: Long): Unit = {
      robot = step.state
      step.outputs.foreach {
        case SecureStream.Transmit(d) =>
          // Segments are raw bytes, not protobuf: no encoding cost, only the serial send.
          firmware = firmware.send(Outgoing(ex.cid, ArraySeq.unsafeWrapArray(d)))
        case SecureStream.Deliver(payload) =>
          if (payload.nonEmpty) delivered += payload(0) & 0xff
          deliveredCount += 1
          lastDeliveryAt = now
        case SecureStream.Acknowledged(_) | SecureStream.Expired(_) => ()
      }
    }
  }
}
