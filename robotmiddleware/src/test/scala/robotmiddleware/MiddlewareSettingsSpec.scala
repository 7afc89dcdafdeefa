package robotmiddleware

import scala.concurrent.duration._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.access.RestartBackoff
import naogateway.testkit.SettingsTables

/** The middleware's keys: their defaults in reference.conf, and a bad value's error naming the key
  * (docs/configuration.md).
  */
class MiddlewareSettingsSpec extends AnyWordSpec with Matchers with SettingsTables {

  private def settings(overrides: String = ""): MiddlewareSettings =
    overriding("robotmiddleware")(MiddlewareSettings.fromConfig)(overrides)

  "The middleware's settings" should {
    "read every limit, back-off and ask timeout from reference.conf" in {
      val s = settings()
      s shouldBe MiddlewareSettings(
        lowBattery = 10.8,
        batteryOk = 11.0,
        walkRefresh = 200.millis,
        callTimeout = 2.seconds,
        postureTimeout = 5.seconds,
        linkStatsInterval = 1.second,
        pendingLimit = 64,
        batteryReadings = 5,
        lookupTimeout = 3.seconds,
        askMargin = 1.second,
        guardRestart = RestartBackoff(200.millis, 5.seconds, 0.2),
        clientAskMargin = 5.seconds,
        clientFindRetry = 200.millis,
        dispatcher = "akka.actor.default-dispatcher",
        servoLimits = ServoLimits(hotCelsius = 65, lowVolts = 10.0),
        limits = ArgumentLimits(speed = 0.3, turn = 1.0)
      )
      // Code that builds the settings with the first seven figures (the specs) gets reference.conf's for the rest.
      MiddlewareSettings(10.8, 11.0, 200.millis, 2.seconds, 5.seconds, 1.second, 64) shouldBe s
      settings("walk-limits.speed = 0.5").limits shouldBe ArgumentLimits(0.5, 1.0)
      settings("lookup-timeout = 500ms").lookupTimeout shouldBe 500.millis
      settings("client.ask-margin = 20s").clientAskMargin shouldBe 20.seconds
      settings("dispatcher = \"naogateway.dispatcher\"").dispatcher shouldBe "naogateway.dispatcher"
      settings("servos { hot = 60, low-voltage = 9.5 }").servoLimits shouldBe ServoLimits(60, 9.5)
    }

    "refuse a bad value with a message naming the key" in {
      refusesWith(settings)(
        "lookup-timeout = 0s" -> "requirement failed: lookup-timeout must be positive",
        "ask-margin = 0s" -> "requirement failed: ask-margin must be positive",
        "client.ask-margin = 0s" -> "requirement failed: client.ask-margin must be positive",
        "client.find-retry = 1ms" -> "requirement failed: client.find-retry must be at least 10 ms",
        "dispatcher = \" \"" -> "requirement failed: dispatcher must name a dispatcher's config path",
        "servos.hot = 0" -> "requirement failed: servos.hot must be from 1 to 100 °C",
        "servos.low-voltage = 0" -> "requirement failed: servos.low-voltage must be from 0 to 20 V",
        "supervision.guard.min-backoff = 10s" ->
          "supervision.guard: a restart back-off needs 0 < min-backoff <= max-backoff"
      )
      an[com.typesafe.config.ConfigException] should be thrownBy settings("lookup-timeout = soon")
    }
  }
}
