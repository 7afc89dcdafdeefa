package bench

import scala.collection.immutable.ListMap
import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.ActorTestKit

import naogateway.access.RobotAccess
import naogateway.api.CallResult
import naogateway.integration.{GatewayFixture, HostileTraffic}
import naogateway.wire.RpcCall

/** `./sbt "bench flood"`: a gateway with its default bounds (discovery.max-robots 16, forget-unreached-after 10 s) and
  * two simulated robots, under the hostile-network flood of `HostileTraffic.flood` at four times the test suite's size:
  * about 360,000 datagrams over 40 rounds (160,000 random and mutated datagrams, 24,000 keep-alives with invented robot
  * ids from one socket and 16,000 from 200 addresses, 4,000 untrusted GameController packets, forged keep-alives from
  * robot 1's address).
  *
  * `flood_robot_actors_max`: the most robot actors the gateway had (sampled twice a round; the cap plus the configured
  * robots is the bound). `flood_log_lines`: log lines at INFO and above during the flood. `flood_heap_growth_bytes`:
  * heap in use after a full collection, after the flood minus before. `flood_robots_answering`: the real robots that
  * answered `system.ping` afterwards (2 of 2). The signed-frames figure `forged_state_changes` belongs beside these
  * once the gateway requires signatures.
  */
object FloodBench extends Benchmark {
  val name = "flood"

  def run(): ListMap[String, Double] = {
    val testKit = ActorTestKit("flood")
    val log = new HostileTraffic.LogLines
    try {
      val f = new GatewayFixture(
        testKit,
        "competition.enabled = on\ngame-controller.trusted-sources = [\"127.0.0.1\"]\n" +
          "game-controller.gate-open-after = 1s"
      )
      try {
        val at1 = HostileTraffic.twoRobotsOnline(f)
        // Competition mode starts closed: the trusted GameController opens it (docs/protocol.md 10.7).
        val gc = java.nio.channels.DatagramChannel.open().bind(new java.net.InetSocketAddress("127.0.0.1", 0))
        try f.openGate(gc)
        finally gc.close()
        val heapBefore = HostileTraffic.usedHeapAfterGc()
        val linesBefore = log.count
        val started = System.nanoTime()
        val flood = HostileTraffic.flood(f, at1.getAddress, rounds = 40, scale = 4, seed = 42)
        val seconds = (System.nanoTime() - started) / 1e9
        val lines = log.count - linesBefore
        val answering = Seq(1, 2).count { id =>
          val probe = testKit.createTestProbe[CallResult]()
          f.open(id).response ! RobotAccess.Call(RpcCall("system", "ping", Vector.empty), probe.ref)
          probe.receiveMessage(10.seconds).result.isRight
        }
        val growth = HostileTraffic.usedHeapAfterGc() - heapBefore
        println(f"flood: ${flood.datagrams} datagrams in $seconds%.1f s; ${log.top(6).mkString("; ")}")
        println(s"flood: refused ${f.stats().rejected.toVector.sortBy(-_._2).mkString(", ")}")
        ListMap(
          "flood_datagrams" -> flood.datagrams.toDouble,
          "flood_robot_actors_max" -> flood.robotActorsMax.toDouble,
          "flood_log_lines" -> lines.toDouble,
          "flood_heap_growth_bytes" -> growth.toDouble,
          "flood_robots_answering" -> answering.toDouble
        )
      } finally f.stop()
    } finally {
      log.close()
      testKit.shutdownTestKit()
    }
  }
}
