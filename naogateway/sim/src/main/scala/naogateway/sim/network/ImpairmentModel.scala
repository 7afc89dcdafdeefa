package naogateway.sim.network

import scala.concurrent.duration._
import naogateway.sim.SeededRandom

/** Why a datagram was dropped. */
sealed trait DropCause extends Product with Serializable

/** The causes of a drop. */
object DropCause {

  /** Random loss. */
  case object Loss extends DropCause

  /** The direction (or the whole network) was partitioned. */
  case object Partition extends DropCause
}

/** What happens to one datagram. */
sealed trait Decision extends Product with Serializable

/** The possible fates of a datagram. */
object Decision {

  /** The datagram is not delivered. */
  final case class Drop(cause: DropCause) extends Decision

  /** One copy is sent per delay, each after its delay from the moment the datagram was received. */
  final case class Deliver(delays: List[FiniteDuration], reordered: Boolean) extends Decision {
    require(delays.lengthCompare(1) == 0 || delays.lengthCompare(2) == 0, s"one or two copies, got ${delays.size}")

    /** Whether a second copy is sent. */
    def duplicated: Boolean = delays.lengthCompare(2) == 0
  }
}

/** The pure decision function of the lossy network: settings and random state in, fate of a datagram out. */
object ImpairmentModel {

  /** The generator of one direction of one proxy, derived from the network seed and the proxy's creation index.
    *
    * Each stream gets its own generator so that traffic on one proxy or direction never shifts the decisions of
    * another.
    */
  def stream(seed: Long, proxyIndex: Int, direction: Direction): SeededRandom =
    SeededRandom.derive(seed, 2L * proxyIndex + (if (direction == Direction.Uplink) 0L else 1L))

  /** Every datagram consumes exactly this many draws, whatever the settings and the outcome.
    *
    * So the n-th datagram's fate depends only on the seed, n and the settings at that moment: changing a setting (or
    * partitioning) never shifts the random values later datagrams see.
    */
  val DrawsPerDatagram: Int = 6

  /** The fate of the next datagram under `impairment`, and the random state for the one after it.
    *
    * The datagram's contents do not matter; only its position in the sequence does.
    */
  def decide(impairment: Impairment, rng: SeededRandom): (Decision, SeededRandom) = {
    val (lossDraw, r1) = rng.nextDouble
    val (duplicationDraw, r2) = r1.nextDouble
    val (reorderDraw, r3) = r2.nextDouble
    val (extraDraw, r4) = r3.nextDouble
    val (firstJitterDraw, r5) = r4.nextDouble
    val (secondJitterDraw, next) = r5.nextDouble

    val decision =
      if (impairment.partitioned) Decision.Drop(DropCause.Partition)
      else if (lossDraw < impairment.loss) Decision.Drop(DropCause.Loss)
      else {
        val reordered = reorderDraw < impairment.reordering && impairment.reorderMaxDelay > Duration.Zero
        // 1 - draw lies in (0, 1], so a held-back datagram always waits a little and at most the maximum.
        val extra = if (reordered) ((1.0 - extraDraw) * impairment.reorderMaxDelay.toNanos).toLong else 0L
        def copyDelay(jitterDraw: Double): FiniteDuration =
          (impairment.delay.toNanos + (jitterDraw * impairment.jitter.toNanos).toLong + extra).nanos
        val first = copyDelay(firstJitterDraw)
        val delays =
          if (duplicationDraw < impairment.duplication) List(first, copyDelay(secondJitterDraw)) else List(first)
        Decision.Deliver(delays, reordered)
      }
    (decision, next)
  }
}
