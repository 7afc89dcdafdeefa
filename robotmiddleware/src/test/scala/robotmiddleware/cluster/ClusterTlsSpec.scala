package robotmiddleware.cluster

import java.nio.file.{Files, Path}

import scala.jdk.CollectionConverters._

import com.typesafe.config.{Config, ConfigFactory}
import org.scalatest.BeforeAndAfterAll
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.testkit.TempFiles
import robotmiddleware.cluster.ClusterTls.{Transport, TeamStores}

/** The cluster's transport decision: plain TCP only on loopback, TLS with the team's two files anywhere, and one line
  * naming the setting when a node must not start. The decision is pure (the store check is passed in); the store check
  * itself runs on files keytool makes as docs/cluster.md shows.
  */
class ClusterTlsSpec extends AnyWordSpec with Matchers with BeforeAndAfterAll {

  private val Secret = "hunter2-never-shown"

  private def node(role: String, settings: String): Config =
    MiddlewareCluster.layered(role, ConfigFactory.parseString(settings), ConfigFactory.empty(), ConfigFactory.empty())

  private def gateway(settings: String = ""): Config = node(MiddlewareCluster.GatewayRole, settings)
  private def app(settings: String = ""): Config = node(MiddlewareCluster.AppRole, settings)

  private val storesSet =
    s"""robotmiddleware.cluster.tls { key-store = "/team/keystore.p12", key-store-password = "$Secret"
       |  trust-store = "/team/truststore.p12", trust-store-password = "$Secret-2" }""".stripMargin

  // Store checks for the decision's tests: one that finds nothing wrong, one for cases that must not reach it.
  private val noProblem: TeamStores => Option[String] = _ => None
  private val neverAsked: TeamStores => Option[String] = _ => fail("the stores must not be checked here")

  "ClusterTls.isLoopback" should {
    "take only addresses written as loopback, never a name that could resolve elsewhere" in {
      Seq("127.0.0.1", "127.1.2.3", "localhost", "LOCALHOST", "::1", "[::1]", "0:0:0:0:0:0:0:1", "0000::0001")
        .filterNot(ClusterTls.isLoopback) shouldBe empty
      Seq(
        "0.0.0.0",
        "192.168.1.42",
        "128.0.0.1",
        "127.0.0.256",
        "",
        "::",
        "base-station.local",
        "::2",
        "fe80::1",
        "::ffff:127.0.0.1",
        "abc:1",
        "<getHostAddress>",
        "<getHostName>",
        "localhost.example.org",
        "127.0.0.1.example.org"
      )
        .filter(ClusterTls.isLoopback) shouldBe empty
    }
  }

  "ClusterTls.decide" should {
    "run plain TCP when the gateway and an app are on loopback and no store is set" in {
      ClusterTls.decide(gateway(), neverAsked) shouldBe Right(Transport.PlainLoopback)
      ClusterTls.decide(app(), neverAsked) shouldBe Right(Transport.PlainLoopback)
      MiddlewareCluster.config(MiddlewareCluster.GatewayRole, application = ConfigFactory.empty())
        .getString("akka.remote.artery.transport") shouldBe "tcp"
    }

    "refuse a gateway whose hostname is off loopback without the stores, naming the setting and what to set" in {
      val line = ClusterTls.decide(gateway("robotmiddleware.cluster.hostname = \"192.168.1.10\""), neverAsked)
      line.isLeft shouldBe true
      line.left.toOption.get should startWith("robotmiddleware.cluster.hostname (ROBOTS_HOSTNAME) is 192.168.1.10")
      line.left.toOption.get should include("robotmiddleware.cluster.tls.key-store (ROBOTS_TLS_KEY_STORE)")
      line.left.toOption.get should include("robotmiddleware.cluster.tls.trust-store (ROBOTS_TLS_TRUST_STORE)")
    }

    "refuse an app whose gateway is off loopback, a bind address off loopback, and a hostname given by name" in {
      def refusal(c: Config): String = ClusterTls.decide(c, neverAsked).left.toOption.get
      refusal(app("robotmiddleware.cluster.gateway-host = \"192.168.1.10\"")) should startWith(
        "robotmiddleware.cluster.gateway-host (ROBOTS_GATEWAY_HOST) is 192.168.1.10")
      refusal(gateway("akka.remote.artery.bind.hostname = \"0.0.0.0\"")) should startWith(
        "akka.remote.artery.bind.hostname is 0.0.0.0")
      refusal(app("robotmiddleware.cluster.hostname = \"<getHostAddress>\"")) should startWith(
        "robotmiddleware.cluster.hostname (ROBOTS_HOSTNAME) is <getHostAddress>")
      refusal(app("akka.cluster.seed-nodes = [\"akka://robots@base-station:25520\"]")) should startWith(
        "akka.cluster.seed-nodes is base-station")
    }

    "refuse half a setup: one store without the other, or a store without its password" in {
      ClusterTls.decide(gateway("robotmiddleware.cluster.tls.key-store = \"/k.p12\""), neverAsked) shouldBe
        Left("robotmiddleware.cluster.tls.trust-store (ROBOTS_TLS_TRUST_STORE) is not set, but the key store is: " +
          "TLS needs both")
      ClusterTls.decide(gateway("robotmiddleware.cluster.tls.trust-store = \"/t.p12\""), neverAsked) shouldBe
        Left("robotmiddleware.cluster.tls.key-store (ROBOTS_TLS_KEY_STORE) is not set, but the trust store is: " +
          "TLS needs both")
      ClusterTls.decide(
        gateway("robotmiddleware.cluster.tls { key-store = \"/k.p12\", trust-store = \"/t.p12\" }"),
        neverAsked) shouldBe
        Left("robotmiddleware.cluster.tls.key-store-password (ROBOTS_TLS_KEY_STORE_PASSWORD) is not set")
    }

    "run TLS with the stores, off loopback and on it, with mutual authentication and the configured version" in {
      val offLoopback = ClusterTls.decide(gateway(s"robotmiddleware.cluster.hostname = \"192.168.1.10\"\n$storesSet"),
        noProblem)
      val onLoopback = ClusterTls.decide(gateway(storesSet), noProblem)
      offLoopback shouldBe onLoopback
      val stores = onLoopback match {
        case Right(Transport.Tls(s)) => s
        case other                   => fail(s"TLS expected, got $other")
      }
      stores.keyStore.toString shouldBe "/team/keystore.p12"
      stores.protocol shouldBe "TLSv1.3"
      val akka = ClusterTls.akkaConfig(Transport.Tls(stores))
      akka.getString("akka.remote.artery.transport") shouldBe "tls-tcp"
      val engine = akka.getConfig("akka.remote.artery.ssl.config-ssl-engine")
      engine.getString("key-store") shouldBe "/team/keystore.p12"
      engine.getString("key-store-password") shouldBe Secret
      engine.getString("key-password") shouldBe Secret
      engine.getString("trust-store") shouldBe "/team/truststore.p12"
      engine.getString("trust-store-password") shouldBe s"$Secret-2"
      engine.getString("protocol") shouldBe "TLSv1.3"
      engine.getStringList("enabled-algorithms").asScala should contain("TLS_AES_256_GCM_SHA384")
      engine.getBoolean("require-mutual-authentication") shouldBe true
      engine.getBoolean("hostname-verification") shouldBe false
    }

    "refuse with the store check's line, and show no password in any line or in the stores' string" in {
      val refused = ClusterTls.decide(gateway(storesSet), _ => Some("the key store is broken"))
      refused shouldBe Left("the key store is broken")
      val stores = ClusterTls.decide(gateway(storesSet), noProblem).toOption.get
      stores.toString should not include Secret
      val lines = Seq(
        ClusterTls.decide(gateway("robotmiddleware.cluster.tls.key-store = \"/k.p12\"\n" +
            s"robotmiddleware.cluster.tls.key-store-password = \"$Secret\""), neverAsked),
        ClusterTls.decide(gateway(storesSet), ClusterTls.storeProblem)
      ).flatMap(_.left.toOption)
      lines should have size 2
      lines.foreach(_ should not include Secret)
    }
  }

  "MiddlewareCluster.config" should {
    "throw the refusal as IllegalArgumentException (the launcher's config-error path), and start no node" in {
      val e = the[IllegalArgumentException] thrownBy MiddlewareCluster.config(MiddlewareCluster.AppRole,
        ConfigFactory.parseString("robotmiddleware.cluster.hostname = \"10.0.0.5\""),
        application = ConfigFactory.empty())
      e.getMessage should startWith("cluster: robotmiddleware.cluster.hostname (ROBOTS_HOSTNAME) is 10.0.0.5")
      an[IllegalArgumentException] should be thrownBy MiddlewareCluster.start[Nothing](
        akka.actor.typed.scaladsl.Behaviors.empty, MiddlewareCluster.AppRole,
        ConfigFactory.parseString("robotmiddleware.cluster.gateway-host = \"10.0.0.1\""))
    }
  }

  // The store check on real files, made by keytool as docs/cluster.md shows.
  private lazy val dir: Path = Files.createTempDirectory("cluster-tls-spec")
  private lazy val tool: Path = TeamKeys.keytool.getOrElse(cancel("the JDK's keytool is not beside this JVM"))
  private lazy val team = TeamKeys.team(tool, dir, "team-keys-0001", "team-trust-0001")
  private lazy val stranger =
    TeamKeys.stranger(tool, Files.createDirectories(dir.resolve("stranger")), team.certificate, "stranger-0001")

  override protected def afterAll(): Unit = {
    TempFiles.deleteRecursively(dir)
    super.afterAll()
  }

  private def check(s: TeamKeys.Stores): Option[String] =
    ClusterTls.decide(s.config.withFallback(gateway()), ClusterTls.storeProblem).left.toOption

  "ClusterTls.storeProblem" should {
    "accept the team's two files as keytool makes them" in {
      check(team.stores) shouldBe None
    }

    "name the setting of a missing file, a wrong password, a store without a key, and a trust store that does not " +
      "trust the key" in {
        val s = team.stores
        check(s.copy(keyStore = dir.resolve("nowhere.p12"))).get should startWith(
          s"robotmiddleware.cluster.tls.key-store (ROBOTS_TLS_KEY_STORE): ${dir.resolve("nowhere.p12")} is not a " +
            "readable file")
        val wrong = check(s.copy(keyStorePassword = "not-the-password")).get
        wrong should include("robotmiddleware.cluster.tls.key-store-password (ROBOTS_TLS_KEY_STORE_PASSWORD)")
        wrong should not include "not-the-password"
        check(s.copy(trustStorePassword = "not-the-password")).get should include(
          "robotmiddleware.cluster.tls.trust-store-password (ROBOTS_TLS_TRUST_STORE_PASSWORD)")
        check(s.copy(keyStore = s.trustStore, keyStorePassword = s.trustStorePassword)).get should endWith(
          "holds no private key")
        check(s.copy(trustStore = s.keyStore, trustStorePassword = s.keyStorePassword)).get should endWith(
          "holds no certificate to trust")
        // The stranger's key under the team's name, checked against the team's trust store.
        check(s.copy(keyStore = stranger.keyStore, keyStorePassword = stranger.keyStorePassword)).get should include(
          "does not trust the certificate")
      }
  }
}
