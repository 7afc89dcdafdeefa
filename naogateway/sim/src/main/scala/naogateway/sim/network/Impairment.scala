package naogateway.sim.network

import scala.concurrent.duration._

/** One direction of a proxied link. */
sealed trait Direction extends Product with Serializable

/** The two directions of a proxy. */
object Direction {

  /** Robot to gateway. */
  case object Uplink extends Direction

  /** Gateway to robot. */
  case object Downlink extends Direction

  /** Both directions, uplink first. */
  val both: List[Direction] = List(Uplink, Downlink)
}

/** How one direction of a proxy mistreats its datagrams.
  *
  * @param loss
  *   probability that a datagram is dropped
  * @param duplication
  *   probability that a delivered datagram is sent twice
  * @param reordering
  *   probability that a delivered datagram is held back by an extra delay, so later ones overtake it
  * @param reorderMaxDelay
  *   the largest extra delay of a held-back datagram (drawn uniformly from (0, max])
  * @param delay
  *   base delay of every delivered copy
  * @param jitter
  *   each copy waits an extra delay drawn uniformly from [0, jitter)
  * @param partitioned
  *   when set, every datagram in this direction is dropped
  */
final case class Impairment(
    loss: Double = 0.0,
    duplication: Double = 0.0,
    reordering: Double = 0.0,
    reorderMaxDelay: FiniteDuration = 20.millis,
    delay: FiniteDuration = Duration.Zero,
    jitter: FiniteDuration = Duration.Zero,
    partitioned: Boolean = false
) {
  require(Impairment.isProbability(loss), s"loss must be in [0, 1], got $loss")
  require(Impairment.isProbability(duplication), s"duplication must be in [0, 1], got $duplication")
  require(Impairment.isProbability(reordering), s"reordering must be in [0, 1], got $reordering")
  require(
    Impairment.isDelay(reorderMaxDelay),
    s"reorderMaxDelay must be in [0, ${Impairment.MaxDelay}], got $reorderMaxDelay"
  )
  require(Impairment.isDelay(delay), s"delay must be in [0, ${Impairment.MaxDelay}], got $delay")
  require(Impairment.isDelay(jitter), s"jitter must be in [0, ${Impairment.MaxDelay}], got $jitter")

  /** The same settings with the partition switch set to `on`. */
  def withPartition(on: Boolean): Impairment = copy(partitioned = on)
}

/** Defaults and limits of [[Impairment]]. */
object Impairment {

  /** Upper bound of each delay setting; it keeps sums of delays far from overflowing and runs finite. */
  val MaxDelay: FiniteDuration = 1.minute

  // Declared after MaxDelay: constructing it validates against MaxDelay, which must be initialised by then.
  /** A perfect link: nothing lost, duplicated, reordered or delayed. */
  val Off: Impairment = Impairment()

  private def isProbability(p: Double): Boolean = p >= 0.0 && p <= 1.0

  private def isDelay(d: FiniteDuration): Boolean = d >= Duration.Zero && d <= MaxDelay
}
