package naogateway.integration

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.RobotAccess
import naogateway.api.{LinkStats, RobotRestarted, RobotStatusUpdated}
import naogateway.sim.{RobotClock, SimulatedRobot}
import naogateway.sim.network.{Impairment, LossyNetwork}
import naogateway.testkit.TestLoopback

/** A gateway and a simulated robot whose clock has a known offset and drift, over a lossy, jittery loopback link. */
class ClockSyncIntegrationSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  "The gateway" must {
    "estimate a robot's clock from its keep-alives alone, within the estimate's own bound, and start again when it restarts" in {
      val f = new GatewayFixture(testKit)
      val network = LossyNetwork.start(seed = 14)
      try {
        val proxy = network.addProxy(f.addresses.robots, TestLoopback.address(),
          uplink = Impairment(loss = 0.2, jitter = 20.millis))
        val clock = RobotClock(offset = 987654.millis, driftPpm = 250.0)
        val (robot, _) = f.robot(9, to = proxy.clientSide, firmware = _.copy(clock = clock))
        // Generous: about 30 keep-alives at 20 % loss take 8 s; the bound need not be small, only true.
        val snapshot = f.awaitEvent(60.seconds) {
          case RobotStatusUpdated(s) if s.robotId == 9 && s.clock.exists(_.samples >= 30) => s
        }
        val truth = f.view(robot)
        truth.clock shouldBe clock
        val estimate = snapshot.clock.get
        val errorMs = (estimate.gatewayNanos - truth.gatewayNanosOf(estimate.robotMillis)) / 1e6
        withClue(s"estimate $estimate, drift ${estimate.driftPpm} ppm: ") {
          math.abs(errorMs) should be <= estimate.errorBoundMillis
          // The keep-alive's own timestamp on the gateway's clock, next to its robot time.
          val stamped = snapshot.stampedAtNanos.get
          math.abs(stamped - truth.gatewayNanosOf(snapshot.uptimeMillis.get)) / 1e6 should be <=
            estimate.errorBoundAt(snapshot.uptimeMillis.get)
          stamped should be <= snapshot.receivedAtNanos
          // Ten seconds back along the fitted drift, still within the bound that grows with the distance.
          val earlier = estimate.robotMillis - 10000
          math.abs(estimate.toGatewayNanos(earlier) - truth.gatewayNanosOf(earlier)) / 1e6 should be <= estimate.errorBoundAt(
            earlier)
        }
        // The link figures carry the same estimate.
        val stats = createTestProbe[LinkStats]()
        f.robotAccess(9) ! RobotAccess.GetLinkStats(stats.ref)
        stats.receiveMessage().clock should not be empty

        robot ! SimulatedRobot.PowerCycle(500.millis)
        f.awaitEvent(20.seconds) { case RobotRestarted(9, _, _) => () }
        // The old clock is forgotten at once: the first keep-alive of the new session has no estimate behind it.
        f.awaitEvent(5.seconds) { case RobotStatusUpdated(s) if s.robotId == 9 => s }.clock shouldBe None
        val again = f.awaitEvent(60.seconds) {
          case RobotStatusUpdated(s) if s.robotId == 9 && s.clock.exists(_.samples >= 20) => s.clock.get
        }
        val rebooted = f.view(robot)
        math.abs(again.gatewayNanos - rebooted.gatewayNanosOf(again.robotMillis)) / 1e6 should be <= again.errorBoundMillis
      } finally {
        f.stop()
        network.stop()
      }
    }
  }
}
