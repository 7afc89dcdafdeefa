package naogateway.launcher

import java.net.InetAddress
import java.nio.file.{Files, Paths}

import com.typesafe.config.ConfigFactory
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** Which doors the launcher opens: all of them beside the demo's simulated robots, none for real robots unless the
  * config names them, and none of the token-less ones off loopback.
  */
class LauncherDoorsSpec extends AnyWordSpec with Matchers {

  private final case class Exited(code: Int) extends RuntimeException(s"exit $code")

  private val noApplication = ConfigFactory.empty()

  /** The purposes of the door ports the launcher would bind with `file`. */
  private def doors(file: String): Set[String] = {
    val c = Launcher.nodeConfig(ConfigFactory.parseString(file), noApplication)
    Preflight.ports(c).map(_.purpose).toSet.intersect(
      Set("the ZeroMQ request socket", "the ZeroMQ publish socket", "the datagram door", "the web view"))
  }

  private val all = Set("the ZeroMQ request socket", "the ZeroMQ publish socket", "the datagram door", "the web view")

  /** The example config for real robots, as the package ships it. */
  private lazy val robotsExample: String = {
    val candidates = Seq(Paths.get("apps/launcher/src/universal/conf/robots.example.conf"),
      Paths.get("src/universal/conf/robots.example.conf"))
    new String(Files.readAllBytes(candidates.find(Files.exists(_)).get), "UTF-8")
  }

  /** The launcher's checks over `file`, with every port free: (lines, exit code). */
  private def check(file: String): (Vector[String], Option[Int]) = {
    val lines = Vector.newBuilder[String]
    val code =
      try {
        Launcher.checked(ConfigFactory.parseString(file), c => throw Exited(c), lines += _, noApplication,
          _ => Preflight.Probe.Free, (_: InetAddress) => true); None
      } catch { case Exited(c) => Some(c) }
    (lines.result(), code)
  }

  "The launcher's defaults" should {
    "no longer switch any door on themselves" in {
      Seq("apps.zeromq.enabled", "apps.datagram-door.enabled", "apps.web.enabled").foreach { key =>
        (key, Launcher.defaults.hasPath(key)) shouldBe ((key, false))
      }
    }
  }

  "The launcher" should {
    "open every door beside the demo's simulated robots" in {
      doors("") shouldBe all
    }

    "open no door for real robots: none simulated, or any robot listed" in {
      doors("apps.launcher.simulated-robots = 0") shouldBe empty
      doors("naogateway.robots = [ { id = 1, address = \"192.168.1.101\" } ]") shouldBe empty
      doors(robotsExample) shouldBe empty
    }

    "open a door for real robots when the config names it on, and keep one off that it names off" in {
      doors(robotsExample + "\napps.web.enabled = on") shouldBe Set("the web view")
      doors(robotsExample + "\napps.zeromq.enabled = on\napps.datagram-door.enabled = true") shouldBe
        all - "the web view"
      doors("apps.datagram-door.enabled = off") shouldBe all - "the datagram door"
    }

    "refuse to start with a door without a token bound off loopback, in one line naming the key" in {
      val (door, doorExit) = check("apps.datagram-door.bind-address = \"0.0.0.0\"")
      doorExit shouldBe Some(Launcher.ExitConfig)
      door should have size 1
      door.head should startWith("naogateway: config: apps.datagram-door.bind-address 0.0.0.0 is not loopback")
      val (zmq, zmqExit) = check("apps.zeromq.bind = \"tcp://*:5555\"")
      zmqExit shouldBe Some(Launcher.ExitConfig)
      zmq.head should include("apps.zeromq.bind tcp://*:5555 is not loopback")
      val (web, webExit) = check("apps.web.bind-address = \"0.0.0.0\"")
      webExit shouldBe Some(Launcher.ExitConfig)
      web.head should include("apps.web.token must be set")
    }

    "not mind an address off loopback for a door that is off" in {
      check("apps.launcher.simulated-robots = 0\napps.datagram-door.bind-address = \"0.0.0.0\"\n" +
        "apps.launcher.ball-follower-robot = 0\napps.launcher.game-controller = off")._2 shouldBe None
    }

    "warn when the web view listens off loopback with its token, and start" in {
      val (lines, code) = check("apps.web { bind-address = \"0.0.0.0\", token = \"s3cret-token\" }")
      code shouldBe None
      lines shouldBe Vector("naogateway: warning: the web view listens on 0.0.0.0, not loopback: every machine that " +
        "reaches it and has the token (apps.web.token) can watch the robots")
    }
  }
}
