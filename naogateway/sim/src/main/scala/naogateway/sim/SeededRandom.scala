package naogateway.sim

import scala.collection.immutable.ArraySeq

/** The simulator's one SplitMix64 generator: every draw returns the value and the next generator, so a model holding
  * one stays a pure value and replays identically for the same seed (the radio model, the firmware model and the lossy
  * network all draw from it).
  */
final case class SeededRandom(state: Long) {

  /** 64 random bits. */
  def nextLong: (Long, SeededRandom) = {
    val s = state + SeededRandom.Gamma
    (SeededRandom.mix(s), SeededRandom(s))
  }

  /** A uniform double in [0, 1). */
  def nextDouble: (Double, SeededRandom) = {
    val (bits, next) = nextLong
    ((bits >>> 11).toDouble * SeededRandom.DoubleUnit, next)
  }

  /** A uniform double in [from, until); `from` when the range is empty. */
  def between(from: Double, until: Double): (Double, SeededRandom) =
    if (until <= from) (from, this)
    else {
      val (u, next) = nextDouble
      (from + u * (until - from), next)
    }

  /** `n` uniform random bytes. */
  def nextBytes(n: Int): (ArraySeq[Byte], SeededRandom) = {
    val out = new Array[Byte](math.max(0, n))
    var rng = this
    var i = 0
    while (i < out.length) {
      val (bits, next) = rng.nextLong
      rng = next
      var k = 0
      while (k < 8 && i < out.length) {
        out(i) = (bits >>> (8 * k)).toByte
        k += 1
        i += 1
      }
    }
    (ArraySeq.unsafeWrapArray(out), rng)
  }

  /** An independent generator derived from this one, for a second consumer of the same seed. */
  def split(salt: Long): SeededRandom = SeededRandom(nextLong._1 ^ (salt * SeededRandom.Gamma))
}

/** Constants of SplitMix64, and independent streams from one seed. */
object SeededRandom {
  private val Gamma: Long = 0x9e3779b97f4a7c15L
  // 53 bits fill a double's mantissa exactly, so every value is equally likely and 1.0 is never reached.
  private val DoubleUnit: Double = 1.0 / (1L << 53).toDouble

  /** Generator number `stream` of `seed`: streams never shift each other's draws. */
  def derive(seed: Long, stream: Long): SeededRandom = SeededRandom(mix(mix(seed) + Gamma * (stream + 1L)))

  private def mix(z0: Long): Long = {
    val z1 = (z0 ^ (z0 >>> 30)) * 0xbf58476d1ce4e5b9L
    val z2 = (z1 ^ (z1 >>> 27)) * 0x94d049bb133111ebL
    z2 ^ (z2 >>> 31)
  }
}
