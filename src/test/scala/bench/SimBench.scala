package bench

import scala.collection.immutable.ListMap

import naogateway.sim.StreamOverflowExperiment

/** The thesis's overflow experiment (100 payloads of 1 kB, one every 50 ms, right sum 4950) through the simulated
  * GS1500M module and CM-530 loop for the default seed: the robot's sum over the raw link and through the thesis's
  * secure stream (window 1, sequence numbers 0..20), the stream's simulated seconds until the robot had every payload,
  * and its retransmissions. All figures come from simulated time, so they do not depend on the machine.
  */
object SimBench extends Benchmark {
  val name = "sim"

  def run(): ListMap[String, Double] = {
    val c = StreamOverflowExperiment.compare()
    require(c.stream.completed && c.stream.inOrder,
      s"the stream run did not deliver every payload in order: ${c.stream}")
    ListMap(
      "sim_overflow_raw_sum" -> c.raw.sum.toDouble,
      "sim_overflow_stream_sum" -> c.stream.sum.toDouble,
      "sim_overflow_stream_seconds" -> c.stream.seconds,
      "sim_overflow_stream_retransmissions" -> c.stream.retransmissions.toDouble
    )
  }
}
