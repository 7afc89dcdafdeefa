package bench

import scala.collection.immutable.ListMap

import naogateway.sim.StreamPairSimulation
import naogateway.sim.StreamPairSimulation._
import naogateway.wire.stream.StreamSettings

/**
 * Secure-stream goodput on the seeded channel: 100 payloads of 1 kB queued at once over a link limited to the
 * robot's raw-datagram rate (SPEC §9, about 306 kbit/s), delivered bytes per simulated second at 10 % loss divided
 * by the same at 0 % loss, averaged over seeds.
 */
object StreamBench extends Benchmark {
  val name = "stream"

  private val Seeds = 1L to 10L
  private val LinkBitsPerSecond = 306000L

  private def goodput(settings: StreamSettings, loss: Double, seed: Long): Double = {
    val link = LinkSettings.lossy(loss).copy(bitsPerSecond = LinkBitsPerSecond)
    val payloads = (0 until 100).map(i => Array.tabulate[Byte](1000)(j => if (j == 0) i.toByte else (i * 31 + j).toByte))
    val result = StreamPairSimulation.run(SimConfig.symmetric(settings, link, seed), evenlySpaced(Side.A, payloads))
    require(result.completed, s"stream run did not complete (window ${settings.window}, loss $loss, seed $seed)")
    val got = result.side(Side.B).deliveries.map(_.payload(0) & 0xff)
    require(got == (0 until 100), s"stream delivered ${got.size} payloads out of order or incomplete")
    result.goodputBytesPerSecond
  }

  private def ratio(settings: StreamSettings): Double = {
    val clean = Seeds.map(goodput(settings, 0.0, _)).sum / Seeds.size
    val lossy = Seeds.map(goodput(settings, 0.10, _)).sum / Seeds.size
    lossy / clean
  }

  def run(): ListMap[String, Double] = ListMap(
    "stream_goodput_ratio_w1_loss10" -> ratio(StreamSettings.thesis),
    "stream_goodput_ratio_w20_loss10" -> ratio(StreamSettings.selectiveRepeat(20))
  )
}
