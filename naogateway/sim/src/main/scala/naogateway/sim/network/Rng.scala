package naogateway.sim.network

/** A pure SplitMix64 generator: each draw returns the next state, so a decision sequence replays from its seed. */
final case class Rng(state: Long) {

  /** A uniformly distributed 64-bit value and the next state. */
  def nextLong: (Long, Rng) = {
    val next = state + Rng.Gamma
    (Rng.mix(next), Rng(next))
  }

  /** A uniformly distributed value in [0, 1) and the next state. */
  def nextDouble: (Double, Rng) = {
    val (bits, next) = nextLong
    // 53 bits fill a double's mantissa exactly, so every value is equally likely and 1.0 is never reached.
    ((bits >>> 11) * Rng.DoubleUnit, next)
  }
}

/** Seeding of [[Rng]]. */
object Rng {
  private val Gamma = 0x9e3779b97f4a7c15L
  private val DoubleUnit = 1.0 / (1L << 53)

  /** The generator of one direction of one proxy, derived from the network seed and the proxy's creation index.
    *
    * Each stream gets its own generator so that traffic on one proxy or direction never shifts the decisions of
    * another.
    */
  def derive(seed: Long, proxyIndex: Int, direction: Direction): Rng = {
    val stream = 2L * proxyIndex + (if (direction == Direction.Uplink) 0L else 1L)
    Rng(mix(mix(seed) + Gamma * (stream + 1L)))
  }

  private def mix(z0: Long): Long = {
    val z1 = (z0 ^ (z0 >>> 30)) * 0xbf58476d1ce4e5b9L
    val z2 = (z1 ^ (z1 >>> 27)) * 0x94d049bb133111ebL
    z2 ^ (z2 >>> 31)
  }
}
