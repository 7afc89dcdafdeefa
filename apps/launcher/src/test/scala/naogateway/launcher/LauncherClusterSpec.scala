package naogateway.launcher

import java.nio.file.Files

import com.typesafe.config.{Config, ConfigFactory}
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.testkit.TempFiles
import robotmiddleware.cluster.{MiddlewareCluster, TeamKeys}

/** The launcher and its cluster: a gateway node off loopback without the team's files stops before it starts, with one
  * line naming the setting (exit 2); with them, the gateway node and the demo's app node both run TLS.
  */
class LauncherClusterSpec extends AnyWordSpec with Matchers {

  private final case class Exited(code: Int) extends RuntimeException(s"exit $code")

  /** The launcher's checks over `file` with every port free: (lines, exit code). */
  private def check(file: Config): (Vector[String], Option[Int]) = {
    val lines = Vector.newBuilder[String]
    val code =
      try {
        Launcher.checked(file, c => throw Exited(c), lines += _, ConfigFactory.empty(),
          _ => Preflight.Probe.Free, _ => true); None
      } catch { case Exited(c) => Some(c) }
    (lines.result(), code)
  }

  "The launcher" should {
    "refuse a cluster hostname off loopback without the team's files, in one line naming the setting, and exit 2" in {
      val (lines, code) = check(ConfigFactory.parseString("robotmiddleware.cluster.hostname = \"192.168.1.10\""))
      code shouldBe Some(Launcher.ExitConfig)
      lines should have size 1
      lines.head should startWith(
        "naogateway: config: cluster: robotmiddleware.cluster.hostname (ROBOTS_HOSTNAME) is 192.168.1.10, off loopback")
      lines.head should include("robotmiddleware.cluster.tls.key-store (ROBOTS_TLS_KEY_STORE)")
    }

    "run the gateway node and the demo's app node on TLS with the team's files, off loopback too" in {
      val tool = TeamKeys.keytool.getOrElse(cancel("the JDK's keytool is not beside this JVM"))
      val dir = Files.createTempDirectory("launcher-cluster")
      try {
        val team = TeamKeys.team(tool, dir, "launcher-keys-1", "launcher-trust-1")
        val file = team.stores.config.withFallback(
          ConfigFactory.parseString("robotmiddleware.cluster { hostname = \"192.168.1.10\", gateway-host = " +
            "\"192.168.1.10\" }"))
        val (lines, code) = check(file)
        code shouldBe None
        lines shouldBe empty
        val gatewayNode = Launcher.nodeConfig(file, ConfigFactory.empty())
        gatewayNode.getString("akka.remote.artery.transport") shouldBe "tls-tcp"
        val appNode = MiddlewareCluster.config(MiddlewareCluster.AppRole, Launcher.appNodeConfig(gatewayNode),
          application = ConfigFactory.empty())
        appNode.getString("akka.remote.artery.transport") shouldBe "tls-tcp"
        appNode.getString("akka.remote.artery.ssl.config-ssl-engine.trust-store") shouldBe team.stores.trustStore
          .toString
        appNode.getBoolean("akka.remote.artery.ssl.config-ssl-engine.require-mutual-authentication") shouldBe true
        Doctor.clusterFinding(gatewayNode).line shouldBe "ok   cluster: TLSv1.3 with mutual authentication: only " +
          s"nodes with a certificate of ${team.stores.trustStore} can join"
      } finally TempFiles.deleteRecursively(dir)
    }
  }

  "robotctl doctor" should {
    "say how the cluster runs: plain TCP on loopback, or the refusal off loopback without the team's files" in {
      Doctor.clusterFinding(Launcher.nodeConfig(ConfigFactory.empty(), ConfigFactory.empty())).line shouldBe
        "ok   cluster: plain TCP, every cluster address on loopback: only this machine can join"
      val dir = Files.createTempDirectory("doctor-cluster")
      try {
        val file = Files.writeString(dir.resolve("robots.conf"), "robotmiddleware.cluster.hostname = \"10.1.2.3\"\n")
        val out = Vector.newBuilder[String]
        RobotCtl.offlineDoctor("127.0.0.1:1", Some(file.toString), out += _, _ => ()) shouldBe RobotCtl.ExitFailed
        out.result().exists(_.startsWith(
            "FAIL config: cluster: robotmiddleware.cluster.hostname (ROBOTS_HOSTNAME) is 10.1.2.3, off loopback")) shouldBe
          true
      } finally TempFiles.deleteRecursively(dir)
    }
  }
}
