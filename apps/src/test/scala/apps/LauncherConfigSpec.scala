package apps

import com.typesafe.config.ConfigFactory
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import robotmiddleware.cluster.MiddlewareCluster

/** The launcher's config: the demo's defaults, and what its app node shares with the gateway node. */
class LauncherConfigSpec extends AnyWordSpec with Matchers {

  "The demo's app node" should {
    "join the cluster where the gateway node is, with the gateway node's dispatcher size, whatever the file says" in {
      val file = ConfigFactory.parseString("robotmiddleware.cluster.gateway-port = 25620")
      val gatewayNode = MiddlewareCluster.config(MiddlewareCluster.GatewayRole, file.withFallback(Launcher.config(Nil)))
      val appNode = MiddlewareCluster.config(MiddlewareCluster.AppRole, Launcher.appNodeConfig(gatewayNode))
      appNode.getInt("robotmiddleware.cluster.gateway-port") shouldBe 25620
      appNode.getInt("akka.actor.default-dispatcher.fork-join-executor.parallelism-min") shouldBe 2
      appNode.getStringList("akka.cluster.seed-nodes").get(0) should endWith(":25620")
    }
  }

  "A config file that does not exist" should {
    "be named in the error" in {
      the[IllegalArgumentException] thrownBy Launcher.config(Seq("/no/such/robots.conf")) should have message
        "requirement failed: config file /no/such/robots.conf does not exist"
    }
  }
}
