package naogateway.gateway

import scala.concurrent.duration._

import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.testkit.SettingsTables
import naogateway.access.RestartBackoff

/** The keys that bound what the network can make the gateway do (docs/architecture.md 13.1, docs/configuration.md). */
class BoundsSettingsSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks with SettingsTables {

  private def settings(overrides: String = ""): GatewaySettings =
    overriding("naogateway")(GatewaySettings.fromConfig)(overrides)

  "The gateway's settings" should {
    "bound discovery, probes and restarts by default" in {
      val s = settings()
      s.discovery shouldBe DiscoverySettings(enabled = true, maxRobots = 16, forgetUnreachedAfter = 10.seconds,
        forgetOfflineAfter = 120.seconds)
      s.budget.probeShare shouldBe 0.1
      s.budget.probeBytesPerSecond shouldBe 12500L
      s.heartbeat.probeBackoffMax shouldBe 30.seconds
      s.newSessionKeepAlives shouldBe 3
    }

    "read the outbox's queue bound, the backlogs, the snapshot timeout and the restart back-offs from reference.conf" in {
      val s = settings()
      s.budget.queueCapacity shouldBe 1024
      s.robotBacklog shouldBe 256
      s.gatewayBacklog shouldBe 1024
      s.snapshotTimeout shouldBe 1.second
      s.supervision shouldBe SupervisionSettings(
        outbox = RestartBackoff(100.millis, 5.seconds, 0.2),
        robot = RestartBackoff(200.millis, 10.seconds, 0.2),
        robotChildren = RestartBackoff(200.millis, 5.seconds, 0.2)
      )
      // The case class's defaults are the same figures, so code that builds settings by hand behaves as configured.
      s.supervision shouldBe SupervisionSettings()
      settings("budget.queue-capacity = 16").budget.queueCapacity shouldBe 16
      settings("supervision.robot.max-backoff = 30s").supervision.robot.maxBackoff shouldBe 30.seconds
    }

    "refuse a queue bound, backlog, snapshot timeout or back-off that bounds nothing, naming the key" in {
      refusesWith(settings)(
        "budget.queue-capacity = 0" -> "requirement failed: budget.queue-capacity must be between 1 and 1000000",
        "link.robot-backlog = 0" -> "requirement failed: link.robot-backlog must be between 1 and 100000",
        "link.gateway-backlog = 0" -> "requirement failed: link.gateway-backlog must be between 1 and 100000",
        "snapshot-timeout = 0s" -> "requirement failed: snapshot-timeout must be between 10 ms and 1 min",
        "supervision.robot.max-backoff = 100ms" ->
          "supervision.robot: a restart back-off needs 0 < min-backoff <= max-backoff",
        "supervision.robot-children.random-factor = 2" ->
          "supervision.robot-children: a restart back-off's random-factor must be between 0 and 1"
      )
    }

    "name the new key when a config still sets discover-from-keep-alive" in {
      messageOf(settings)("discover-from-keep-alive = off") should include("discovery.enabled")
      settings("discovery.enabled = off").discovery.enabled shouldBe false
    }

    "refuse bounds that bound nothing" in {
      refuses(settings)(
        "discovery.max-robots = -1",
        "discovery.forget-offline-after = 0s",
        "budget.probe-share = 0",
        "new-session.keep-alives = 0",
        "heartbeat.probe-backoff-max = 100ms"
      )
    }
  }

  "The probe back-off" should {
    "double from one round of probes up to the maximum, and never probe more often than one round per back-off" in {
      val hb = settings().heartbeat
      (1 to 8).map(hb.probeBackoff) shouldBe Vector(450, 900, 1800, 3600, 7200, 14400, 28800, 30000).map(_.millis)
      forAll(Gen.choose(1, 10000)) { rounds =>
        hb.probeBackoff(rounds) should (be >= hb.probeRound and be <= hb.probeBackoffMax)
        hb.probeBackoff(rounds + 1) should be >= hb.probeBackoff(rounds)
      }
      // Probing a robot that never answers, wanted all the time: after the first minute at most one round of
      // `chances` probes per 30 s + 450 ms.
      val perHourAfterwards = 3600.0 / (hb.probeBackoffMax + hb.probeRound).toUnit(SECONDS) * hb.chances
      perHourAfterwards should be < 400.0
    }
  }
}
