package naogateway.sim

import java.util.SplittableRandom

import scala.collection.mutable
import scala.concurrent.duration._

import naogateway.wire.stream.{SecureStream, StreamStats, StreamSettings}

/** A deterministic discrete-event simulation of two secure-stream endpoints, A and B, joined by a seeded lossy channel,
  * for tests and benchmarks.
  *
  * Time is simulated (Long nanoseconds from 0); there are no threads and no sleeping, so a run of minutes of link time
  * takes milliseconds, and the same configuration and seed always give the same result. Each direction of the channel
  * loses, duplicates, delays (base delay plus uniform jitter) and reorders (a random extra delay for some datagrams)
  * independently, can be cut completely during outages, and can have a limited bit rate.
  *
  * A run ends when every scheduled payload is settled at its sender (acknowledged, expired or refused), when the
  * simulated time limit is reached, or after `maxEvents` events, whichever comes first.
  */
object StreamPairSimulation {

  /** One of the two endpoints. */
  sealed trait Side extends Product with Serializable {

    /** The endpoint at the other end of the channel. */
    def other: Side
  }

  /** The two endpoints. */
  object Side {

    /** Endpoint A. */
    case object A extends Side {
      def other: Side = B
    }

    /** Endpoint B. */
    case object B extends Side {
      def other: Side = A
    }
  }

  /** A period of simulated time in which a direction of the channel loses everything sent into it. */
  final case class Outage(from: Long, until: Long) {
    require(until >= from, s"an outage must not end ($until) before it starts ($from)")

    /** Whether a datagram sent at `t` falls into the outage. */
    def covers(t: Long): Boolean = t >= from && t < until
  }

  /** How one direction of the channel treats datagrams.
    *
    * @param loss
    *   probability that a datagram is lost
    * @param duplication
    *   probability that a datagram that is not lost arrives twice (each copy delayed independently)
    * @param reordering
    *   probability that a copy gets an extra delay, uniform in [0, reorderDelay], so later datagrams overtake it
    * @param reorderDelay
    *   the largest extra delay of a reordered copy; keep it within about one round trip (see the segment lifetime rule
    *   of SecureStream)
    * @param baseDelay
    *   the fixed one-way delay
    * @param jitter
    *   a uniform random delay in [0, jitter] added to every copy
    * @param bitsPerSecond
    *   the link rate; datagrams queue behind each other at the sender (0 = unlimited)
    * @param outages
    *   periods of total loss
    */
  final case class LinkSettings(
      loss: Double = 0.0,
      duplication: Double = 0.0,
      reordering: Double = 0.0,
      reorderDelay: FiniteDuration = 5.millis,
      baseDelay: FiniteDuration = 5.millis,
      jitter: FiniteDuration = Duration.Zero,
      bitsPerSecond: Long = 0L,
      outages: Vector[Outage] = Vector.empty
  ) {
    require(loss >= 0.0 && loss <= 1.0, s"loss must be a probability, was $loss")
    require(duplication >= 0.0 && duplication <= 1.0, s"duplication must be a probability, was $duplication")
    require(reordering >= 0.0 && reordering <= 1.0, s"reordering must be a probability, was $reordering")
    require(reorderDelay >= Duration.Zero, s"reorderDelay must not be negative, was $reorderDelay")
    require(baseDelay >= Duration.Zero, s"baseDelay must not be negative, was $baseDelay")
    require(jitter >= Duration.Zero, s"jitter must not be negative, was $jitter")
    require(bitsPerSecond >= 0L, s"bitsPerSecond must not be negative, was $bitsPerSecond")
  }

  /** Ready-made channel shapes. */
  object LinkSettings {

    /** No loss, no duplication, no reordering, 5 ms each way. */
    val perfect: LinkSettings = LinkSettings()

    /** The given loss plus the usual nuisances of a WLAN hop: 2 % duplicates, 5 % reordered by up to 5 ms, 2 ms jitter
      * on a 5 ms base delay.
      */
    def lossy(loss: Double): LinkSettings =
      LinkSettings(loss = loss, duplication = 0.02, reordering = 0.05, reorderDelay = 5.millis, jitter = 2.millis)
  }

  /** Everything a run needs besides the payloads.
    *
    * @param timeLimit
    *   simulated time after which the run stops even if payloads are still unsettled
    * @param maxEvents
    *   a bound on processed events, so a run always stops
    */
  final case class SimConfig(
      a: StreamSettings,
      b: StreamSettings,
      aToB: LinkSettings,
      bToA: LinkSettings,
      seed: Long,
      timeLimit: FiniteDuration = 10.minutes,
      maxEvents: Long = 5000000L
  ) {
    require(timeLimit > Duration.Zero, s"timeLimit must be positive, was $timeLimit")
    require(maxEvents > 0L, s"maxEvents must be positive, was $maxEvents")
  }

  /** Convenience constructors. */
  object SimConfig {

    /** Both endpoints with the same settings and both directions with the same channel. */
    def symmetric(settings: StreamSettings, link: LinkSettings, seed: Long): SimConfig =
      SimConfig(settings, settings, link, link, seed)
  }

  /** A payload `from` hands to its endpoint at simulated time `at`; its id in the results is its index in the sequence
    * given to [[run]].
    */
  final case class ScheduledSend(from: Side, at: Long, payload: Array[Byte], deadline: Option[Long] = None)

  /** A payload an endpoint delivered, and when. */
  final case class Delivery(at: Long, payload: Array[Byte])

  /** A payload its sender gave up, and when. */
  final case class Expiry(id: Long, at: Long)

  /** What one direction of the channel did. */
  final case class DirectionStats(datagrams: Long, bytes: Long, lost: Long, duplicated: Long, reordered: Long)

  /** The outcome for one endpoint: what it received and what became of what it sent.
    *
    * @param deliveries
    *   payloads delivered to this side, in order
    * @param acknowledged
    *   ids of own payloads the peer acknowledged, in order
    * @param expired
    *   own payloads that expired
    * @param refused
    *   own sends the endpoint refused
    * @param stats
    *   the endpoint's stats at the end
    * @param finalState
    *   the endpoint at the end, for inspecting the round-trip estimate and the like
    * @param link
    *   what the channel did to the datagrams this side sent
    */
  final case class SideReport(
      deliveries: Vector[Delivery],
      acknowledged: Vector[Long],
      expired: Vector[Expiry],
      refused: Vector[SecureStream.SendRefused],
      stats: StreamStats,
      finalState: SecureStream,
      link: DirectionStats
  ) {

    /** The delivered payloads in order. */
    def delivered: Vector[Array[Byte]] = deliveries.map(_.payload)

    /** Payload bytes delivered to this side. */
    def deliveredBytes: Long = deliveries.iterator.map(_.payload.length.toLong).sum
  }

  /** The outcome of a run.
    *
    * @param completed
    *   whether every scheduled payload was settled (acknowledged, expired or refused) before a limit struck
    * @param finishedAt
    *   simulated time at which the run ended
    * @param lastDeliveryAt
    *   simulated time of the last delivery on either side (0 if none)
    * @param events
    *   events processed
    */
  final case class SimResult(
      a: SideReport,
      b: SideReport,
      completed: Boolean,
      finishedAt: Long,
      lastDeliveryAt: Long,
      events: Long
  ) {

    /** The report of one side. */
    def side(s: Side): SideReport = s match {
      case Side.A => a
      case Side.B => b
    }

    /** Payload bytes delivered on both sides. */
    def deliveredBytes: Long = a.deliveredBytes + b.deliveredBytes

    /** Payload bytes delivered per simulated second, measured up to the last delivery (0 if nothing arrived). */
    def goodputBytesPerSecond: Double =
      if (lastDeliveryAt <= 0L) 0.0 else deliveredBytes.toDouble * 1e9 / lastDeliveryAt.toDouble
  }

  /** Payloads sent by `from` one after another every `interval`, starting at `start`. */
  def evenlySpaced(
      from: Side,
      payloads: Seq[Array[Byte]],
      start: Long = 0L,
      interval: FiniteDuration = Duration.Zero
  ): Vector[ScheduledSend] =
    payloads.iterator.zipWithIndex.map { case (p, i) => ScheduledSend(from, start + i * interval.toNanos, p) }.toVector

  /** Runs the simulation; deterministic for a given configuration, seed and list of sends. */
  def run(config: SimConfig, sends: Seq[ScheduledSend]): SimResult = new Run(config, sends.toVector).execute()

  private sealed trait Event
  private final case class Enqueue(index: Int) extends Event
  private final case class Arrive(to: Side, datagram: Array[Byte]) extends Event
  private final case class Timer(side: Side) extends Event

  private final case class Scheduled(at: Long, order: Long, event: Event)

  private val earliestFirst: Ordering[Scheduled] = (x: Scheduled, y: Scheduled) => {
    val byTime = java.lang.Long.compare(y.at, x.at)
    if (byTime != 0) byTime else java.lang.Long.compare(y.order, x.order)
  }

  private final val NoTimer = Long.MinValue

  /** One endpoint with everything recorded about it. */
  private final class Endpoint(var state: SecureStream) {
    var timerAt: Long = NoTimer
    val deliveries = Vector.newBuilder[Delivery]
    val acknowledged = Vector.newBuilder[Long]
    val expired = Vector.newBuilder[Expiry]
    val refused = Vector.newBuilder[SecureStream.SendRefused]
  }

  /** One direction of the channel. */
  private final class Link(settings: LinkSettings, random: SplittableRandom) {
    private var freeAt = 0L
    private var datagrams = 0L
    private var bytes = 0L
    private var lost = 0L
    private var duplicated = 0L
    private var reordered = 0L
    private val base = settings.baseDelay.toNanos
    private val jitter = settings.jitter.toNanos
    private val reorderDelay = settings.reorderDelay.toNanos

    /** The arrival times of the copies that survive (none, one or two). */
    def carry(now: Long, size: Int): List[Long] = {
      datagrams += 1
      bytes += size
      val departure =
        if (settings.bitsPerSecond <= 0L) now
        else {
          freeAt = math.max(now, freeAt) + size.toLong * 8L * 1000000000L / settings.bitsPerSecond
          freeAt
        }
      if (settings.outages.exists(_.covers(now)) || random.nextDouble() < settings.loss) {
        lost += 1
        Nil
      } else {
        val copies = if (random.nextDouble() < settings.duplication) { duplicated += 1; 2 }
        else 1
        List.fill(copies) {
          val extra =
            if (random.nextDouble() < settings.reordering) {
              reordered += 1
              if (reorderDelay > 0L) random.nextLong(reorderDelay + 1) else 0L
            } else 0L
          departure + base + (if (jitter > 0L) random.nextLong(jitter + 1) else 0L) + extra
        }
      }
    }

    def stats: DirectionStats = DirectionStats(datagrams, bytes, lost, duplicated, reordered)
  }

  private final class Run(config: SimConfig, sends: Vector[ScheduledSend]) {
    private val queue = mutable.PriorityQueue.empty[Scheduled](earliestFirst)
    private var order = 0L
    private val root = new SplittableRandom(config.seed)
    private val links: Map[Side, Link] =
      Map(Side.A -> new Link(config.aToB, root.split()), Side.B -> new Link(config.bToA, root.split()))
    private val endpoints: Map[Side, Endpoint] =
      Map(
        Side.A -> new Endpoint(SecureStream.initial(config.a, 0L)),
        Side.B -> new Endpoint(SecureStream.initial(config.b, 0L))
      )
    private var settledSends = 0
    private var lastDeliveryAt = 0L
    private val timeLimit = config.timeLimit.toNanos

    private def schedule(at: Long, event: Event): Unit = {
      queue.enqueue(Scheduled(at, order, event))
      order += 1
    }

    def execute(): SimResult = {
      sends.indices.foreach(i => schedule(math.max(0L, sends(i).at), Enqueue(i)))
      List[Side](Side.A, Side.B).foreach(armTimer(_, 0L))
      var now = 0L
      var events = 0L
      var stop = sends.isEmpty
      while (!stop && queue.nonEmpty && events < config.maxEvents) {
        val next = queue.dequeue()
        if (next.at > timeLimit) {
          now = timeLimit
          stop = true
        } else {
          now = next.at
          events += 1
          handle(next.event, now)
          stop = settledSends == sends.length
        }
      }
      val a = report(Side.A)
      val b = report(Side.B)
      SimResult(a, b, settledSends == sends.length, now, lastDeliveryAt, events)
    }

    private def handle(event: Event, now: Long): Unit = event match {
      case Enqueue(i) =>
        val send = sends(i)
        val endpoint = endpoints(send.from)
        endpoint.state.send(send.payload, i.toLong, send.deadline, now) match {
          case Right(step) => apply(send.from, step, now)
          case Left(refusal) =>
            endpoint.refused += refusal
            settledSends += 1
        }
      case Arrive(to, datagram) =>
        apply(to, endpoints(to).state.receive(datagram, now), now)
      case Timer(side) =>
        val endpoint = endpoints(side)
        if (endpoint.timerAt == now) {
          endpoint.timerAt = NoTimer
          apply(side, endpoint.state.tick(now), now)
        }
    }

    private def apply(side: Side, step: SecureStream.Step, now: Long): Unit = {
      val endpoint = endpoints(side)
      endpoint.state = step.state
      step.outputs.foreach {
        case SecureStream.Transmit(datagram) =>
          links(side).carry(now, datagram.length).foreach(at => schedule(at, Arrive(side.other, datagram)))
        case SecureStream.Deliver(payload) =>
          endpoint.deliveries += Delivery(now, payload)
          lastDeliveryAt = now
        case SecureStream.Acknowledged(id) =>
          endpoint.acknowledged += id
          settledSends += 1
        case SecureStream.Expired(id) =>
          endpoint.expired += Expiry(id, now)
          settledSends += 1
      }
      armTimer(side, now)
    }

    private def armTimer(side: Side, now: Long): Unit = {
      val endpoint = endpoints(side)
      endpoint.state.nextTimerAt.foreach { t =>
        val at = math.max(t, now)
        if (at != endpoint.timerAt) {
          endpoint.timerAt = at
          schedule(at, Timer(side))
        }
      }
    }

    private def report(side: Side): SideReport = {
      val endpoint = endpoints(side)
      SideReport(
        endpoint.deliveries.result(),
        endpoint.acknowledged.result(),
        endpoint.expired.result(),
        endpoint.refused.result(),
        endpoint.state.stats,
        endpoint.state,
        links(side).stats
      )
    }
  }

}
