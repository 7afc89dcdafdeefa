package naogateway.gateway

import scala.concurrent.duration._

import com.typesafe.config.ConfigFactory
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** `naogateway.bus-bridge` (docs/protocol.md 6.9): its reference defaults, and a bind address off loopback refused. */
class BusBridgeSettingsSpec extends AnyWordSpec with Matchers {

  private def settings(overrides: String = ""): BusBridgeSettings =
    BusBridgeSettings.fromConfig(
      ConfigFactory.parseString(overrides).withFallback(ConfigFactory.load()).getConfig("naogateway"))

  "the bus bridge's settings" should {
    "be off on loopback at 6100 + robot id by default" in {
      settings() shouldBe BusBridgeSettings(enabled = false, "127.0.0.1", 6100, 1.second)
      settings().portOf(2) shouldBe Some(6102)
      settings("naogateway.bus-bridge.base-port = 65530").portOf(9) shouldBe None
    }
    "refuse a bind address that is not loopback, naming the key" in {
      Seq("0.0.0.0", "192.0.2.7", "").foreach { address =>
        val refused =
          intercept[IllegalArgumentException](settings(s"""naogateway.bus-bridge.bind-address = "$address""""))
        refused.getMessage should include("naogateway.bus-bridge.bind-address")
      }
      settings("""naogateway.bus-bridge.bind-address = "::1"""").bindAddress shouldBe "::1"
    }
  }
}
