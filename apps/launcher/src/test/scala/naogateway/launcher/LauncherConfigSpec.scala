package naogateway.launcher

import com.typesafe.config.{ConfigFactory, ConfigResolveOptions}
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import robotmiddleware.cluster.MiddlewareCluster

/** The launcher's config: the demo's defaults, what outranks them, and what its app node shares with the gateway node.
  */
class LauncherConfigSpec extends AnyWordSpec with Matchers {

  private val noApplication = ConfigFactory.empty()

  "The demo's app node" should {
    "join the cluster where the gateway node is, with the gateway node's dispatcher sizes, whatever the file says" in {
      val file = ConfigFactory.parseString("robotmiddleware.cluster.gateway-port = 25620")
      val gatewayNode = Launcher.nodeConfig(file, noApplication)
      val appNode = MiddlewareCluster.config(MiddlewareCluster.AppRole, Launcher.appNodeConfig(gatewayNode))
      appNode.getInt("robotmiddleware.cluster.gateway-port") shouldBe 25620
      // One thread for each of Akka's pools on both nodes, not Akka's 8, 4 and 2: fewer threads woken for nothing.
      Seq("akka.actor.default-dispatcher", "akka.actor.internal-dispatcher", "akka.remote.default-remote-dispatcher")
        .foreach { pool =>
          withClue(pool)(appNode.getInt(s"$pool.fork-join-executor.parallelism-max") shouldBe 1)
          withClue(pool)(gatewayNode.getInt(s"$pool.fork-join-executor.parallelism-max") shouldBe 1)
        }
      appNode.getStringList("akka.cluster.seed-nodes").get(0) should endWith(":25620")
      // Its scheduler wakes 20 times a second, not 100, and the cluster's tasks run on it rather than on one of their
      // own (which Akka starts when the cluster's tick is the shorter).
      appNode.getDuration("akka.scheduler.tick-duration").toMillis shouldBe 50L
      appNode.getDuration("akka.cluster.scheduler.tick-duration") shouldBe appNode.getDuration(
        "akka.scheduler.tick-duration")
      // The gateway node's wakes 50 times a second, still finer than the cluster's tick (33 ms), so the cluster's
      // tasks share it there too.
      gatewayNode.getDuration("akka.scheduler.tick-duration").toMillis shouldBe 20L
      gatewayNode.getDuration("akka.scheduler.tick-duration") should be <= gatewayNode.getDuration(
        "akka.cluster.scheduler.tick-duration")
      // Artery's streams run on the internal dispatcher on both nodes: no message between two of Akka's pools.
      Seq("akka.remote.use-dispatcher", "akka.remote.artery.advanced.use-dispatcher").foreach { key =>
        withClue(key)(gatewayNode.getString(key) shouldBe "akka.actor.internal-dispatcher")
        withClue(key)(appNode.getString(key) shouldBe "akka.actor.internal-dispatcher")
      }
    }

    "shut down as quickly as the gateway node: the same phase timeouts, leader pace and flush wait" in {
      val gatewayNode = Launcher.nodeConfig(ConfigFactory.empty(), noApplication)
      val appNode = MiddlewareCluster.config(MiddlewareCluster.AppRole, Launcher.appNodeConfig(gatewayNode))
      // Akka's defaults (5 s, 10 s, 1 s, 1 s) would let the app node's leave outlast Ctrl-C's 2 s on its own.
      Seq(
        "akka.coordinated-shutdown.default-phase-timeout",
        "akka.coordinated-shutdown.phases.cluster-exiting.timeout",
        "akka.cluster.leader-actions-interval",
        "akka.remote.artery.advanced.shutdown-flush-timeout"
      ).foreach { key =>
        withClue(key)(appNode.getDuration(key) shouldBe gatewayNode.getDuration(key))
        withClue(key)(appNode.getDuration(key).toMillis should be <= 1000L)
      }
      // The phases in one order on both nodes: apps leave before the gateway node does.
      appNode.getStringList("akka.coordinated-shutdown.phases.cluster-exiting.depends-on") shouldBe
        gatewayNode.getStringList("akka.coordinated-shutdown.phases.cluster-exiting.depends-on")
    }
  }

  "The gateway node's config" should {
    "take the launcher's defaults when nothing else is given" in {
      val c = Launcher.nodeConfig(ConfigFactory.empty(), noApplication)
      c.getString("naogateway.link.bind-address") shouldBe "127.0.0.1"
      c.getInt("apps.launcher.simulated-robots") shouldBe 3
      // The middleware beside the robot actors, on their dispatcher, which the same config defines.
      c.getString("robotmiddleware.dispatcher") shouldBe "naogateway.dispatcher"
      c.hasPath("naogateway.dispatcher.executor") shouldBe true
      robotmiddleware.MiddlewareSettings.fromConfig(c.getConfig("robotmiddleware")).dispatcher shouldBe
        "naogateway.dispatcher"
    }

    "let application.conf override the launcher's defaults, and the config file override both" in {
      val application = ConfigFactory.parseString(
        "naogateway.link { bind-address = \"0.0.0.0\", robot-port = 11011 }\napps.launcher.simulated-robots = 0")
      val c = Launcher.nodeConfig(ConfigFactory.empty(), application)
      c.getString("naogateway.link.bind-address") shouldBe "0.0.0.0"
      c.getInt("naogateway.link.robot-port") shouldBe 11011
      c.getInt("apps.launcher.simulated-robots") shouldBe 0
      val file = ConfigFactory.parseString("naogateway.link.robot-port = 11013")
      Launcher.nodeConfig(file, application).getInt("naogateway.link.robot-port") shouldBe 11013
    }

    "let NAOGATEWAY_BIND_ADDRESS and NAOGATEWAY_ROBOT_PORT override the launcher's defaults" in {
      // The environment as the resolver sees it; the launcher resolves against the real one the same way.
      val env = ConfigFactory.parseString("NAOGATEWAY_BIND_ADDRESS = \"0.0.0.0\"\nNAOGATEWAY_ROBOT_PORT = 11011")
      // Variables are looked up from the root, where the environment's stand-in puts them.
      val c = Launcher.defaults.withFallback(env).resolve(ConfigResolveOptions.noSystem())
      c.getString("naogateway.link.bind-address") shouldBe "0.0.0.0"
      c.getInt("naogateway.link.robot-port") shouldBe 11011
      val unset = Launcher.defaults.resolve(ConfigResolveOptions.noSystem())
      unset.getString("naogateway.link.bind-address") shouldBe "127.0.0.1"
      unset.getInt("naogateway.link.robot-port") shouldBe 0
    }
  }

  "A config file that does not exist" should {
    "be named in the error" in {
      the[IllegalArgumentException] thrownBy Launcher.config(Seq("/no/such/robots.conf")) should have message
        "requirement failed: config file /no/such/robots.conf does not exist"
    }
  }
}
