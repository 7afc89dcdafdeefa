package bench

import scala.collection.immutable.ListMap

import naogateway.sim.StreamPairSimulation
import naogateway.sim.StreamPairSimulation._
import naogateway.wire.stream.{SecureStream, StreamSettings}

/** Secure-stream goodput on the seeded channel: 100 payloads of 1 kB queued at once over a link limited to the robot's
  * raw-datagram rate (docs/simulator.md 1.4, about 306 kbit/s), delivered bytes per simulated second, averaged over
  * seeds; each window at 10 % loss against its own lossless run, window 20 against window 1 at 10 % loss, and the
  * link's ceiling that bounds both.
  */
object StreamBench extends Benchmark {
  val name = "stream"

  private val Seeds = 1L to 10L
  private val LinkBitsPerSecond = 306000L
  private val PayloadBytes = 1000
  private val Loss = 0.10

  /** Mean goodput in payload bytes per simulated second, and mean retransmission timeouts per run. */
  private final case class Figures(goodput: Double, timeouts: Double)

  private def once(settings: StreamSettings, loss: Double, seed: Long): SimResult = {
    val link = LinkSettings.lossy(loss).copy(bitsPerSecond = LinkBitsPerSecond)
    val payloads =
      (0 until 100).map(i => Array.tabulate[Byte](PayloadBytes)(j => if (j == 0) i.toByte else (i * 31 + j).toByte))
    val result = StreamPairSimulation.run(SimConfig.symmetric(settings, link, seed), evenlySpaced(Side.A, payloads))
    require(result.completed, s"stream run did not complete (window ${settings.window}, loss $loss, seed $seed)")
    val got = result.side(Side.B).deliveries.map(_.payload(0) & 0xff)
    require(got == (0 until 100), s"stream delivered ${got.size} payloads out of order or incomplete")
    result
  }

  private def measure(settings: StreamSettings, loss: Double): Figures = {
    val runs = Seeds.map(once(settings, loss, _))
    Figures(
      runs.map(_.goodputBytesPerSecond).sum / runs.size,
      runs.map(_.side(Side.A).stats.timeouts.toDouble).sum / runs.size
    )
  }

  def run(): ListMap[String, Double] = {
    val sw = StreamSettings.thesis
    val sr = StreamSettings.selectiveRepeat(20)
    val swClean = measure(sw, 0.0)
    val swLossy = measure(sw, Loss)
    val srClean = measure(sr, 0.0)
    val srLossy = measure(sr, Loss)
    // The serial line carries one datagram (payload plus header) at a time: no window can deliver more than this.
    val ceiling = LinkBitsPerSecond / 8.0 * PayloadBytes / (PayloadBytes + SecureStream.HeaderBytes)
    ListMap(
      "stream_goodput_ratio_w1_loss10" -> swLossy.goodput / swClean.goodput,
      "stream_goodput_ratio_w20_loss10" -> srLossy.goodput / srClean.goodput,
      "stream_sr_over_sw_loss10" -> srLossy.goodput / swLossy.goodput,
      "stream_link_ceiling_bytes_s" -> ceiling,
      "stream_goodput_w1_loss0_bytes_s" -> swClean.goodput,
      "stream_goodput_w20_loss0_bytes_s" -> srClean.goodput,
      "stream_goodput_w1_loss10_bytes_s" -> swLossy.goodput,
      "stream_goodput_w20_loss10_bytes_s" -> srLossy.goodput,
      // Every datagram lost on the way out must go again; a lost ACK costs nothing, as the next one covers it.
      "stream_sr_bound_loss10_bytes_s" -> ceiling * (1.0 - Loss),
      "stream_timeouts_w1_loss10" -> swLossy.timeouts,
      "stream_timeouts_w20_loss10" -> srLossy.timeouts
    )
  }
}
