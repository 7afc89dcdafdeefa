package naogateway.launcher

import java.net.{DatagramSocket, InetAddress, InetSocketAddress, ServerSocket}

import com.typesafe.config.ConfigFactory
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** What the launcher says on the terminal before it starts anything: config problems, ports in use, missing addresses.
  */
class LauncherPreflightSpec extends AnyWordSpec with Matchers {

  private final case class Exited(code: Int) extends RuntimeException(s"exit $code")

  /** The launcher's checks over `file`, with free ports everywhere unless `probe` says otherwise: (lines, exit code).
    */
  private def check(file: String, probe: Preflight.PortUse => Preflight.Probe = _ => Preflight.Probe.Free,
      loopback: InetAddress => Boolean = _ => true): (Vector[String], Option[Int]) = {
    val lines = Vector.newBuilder[String]
    val code =
      try {
        Launcher.checked(ConfigFactory.parseString(file), c => throw Exited(c), lines += _, ConfigFactory.empty(),
          probe, loopback); None
      } catch { case Exited(c) => Some(c) }
    (lines.result(), code)
  }

  "The launcher's checks" should {
    "pass the demo's config on a machine with its ports free" in {
      check("") shouldBe ((Vector.empty, None))
    }

    "name the key of a value of the wrong type in one line, and exit 2" in {
      val (lines, code) = check("naogateway.link.robot-port = eleven")
      code shouldBe Some(Launcher.ExitConfig)
      lines should have size 1
      lines.head should startWith("naogateway: config: ")
      lines.head should include("naogateway.link.robot-port")
      lines.head should include("String: 1")
    }

    "name the key of a value out of range in one line, and exit 2" in {
      val (lines, code) = check("naogateway.link.robot-port = 70000")
      code shouldBe Some(Launcher.ExitConfig)
      lines shouldBe Vector("naogateway: config: link.robot-port 70000 is not a UDP port")
    }

    "say that a robot that must sign needs the team key, in one line, and exit 2" in {
      val (lines, code) = check("""naogateway.robots = [ { id = 1, address = "192.168.1.101", signing = required } ]""")
      code shouldBe Some(Launcher.ExitConfig)
      lines should have size 1
      lines.head should include("signing")
    }

    "warn about a key no reference knows (a typo) and start anyway" in {
      val (lines, code) =
        check("naogateway.competiton.enabled = on\nnaogateway.robots = [ { id = 1, address = \"10.0.0.1\" } ]")
      code shouldBe None
      lines shouldBe Vector(
        "naogateway: warning: config key naogateway.competiton.enabled is not a setting (a typo?); it is ignored")
    }

    "name a port another program holds, what it is for and the setting that moves it, and exit 3" in {
      val held = new ServerSocket()
      held.bind(new InetSocketAddress("127.0.0.1", 0))
      try {
        val port = held.getLocalPort
        val (lines, code) = check(
          s"apps.control.bind = \"127.0.0.1:$port\"\napps.zeromq.enabled = off\napps.datagram-door.enabled = off\napps.web.enabled = off\nrobotmiddleware.cluster.gateway-port = 0\n" +
            "naogateway.game-controller.enabled = off",
          probe = Preflight.probe
        )
        code shouldBe Some(Launcher.ExitPortInUse)
        lines shouldBe Vector(
          s"naogateway: port $port (TCP on 127.0.0.1, the control port robotctl talks to) is in use by another program; " +
            "stop that program or move the port with apps.control.bind (NAOGATEWAY_CONTROL)")
      } finally held.close()
    }

    "name the robots' UDP port when another program (FU-Remote) holds it" in {
      val fuRemote = new DatagramSocket(new InetSocketAddress("127.0.0.1", 0))
      try {
        val port = fuRemote.getLocalPort
        val (lines, code) = check(
          s"naogateway.link.robot-port = $port\napps.zeromq.enabled = off\napps.datagram-door.enabled = off\napps.web.enabled = off\n" +
            "apps.control.enabled = off\n" +
            "robotmiddleware.cluster.gateway-port = 0\nnaogateway.game-controller.enabled = off",
          probe = Preflight.probe
        )
        code shouldBe Some(Launcher.ExitPortInUse)
        lines should have size 1
        lines.head should startWith(s"naogateway: port $port (UDP on 127.0.0.1, the robots' port")
        lines.head should endWith("naogateway.link.robot-port (NAOGATEWAY_ROBOT_PORT)")
      } finally fuRemote.close()
    }

    "only warn when the GameController's port is taken: the gateway runs on with game state unknown" in {
      val (lines, code) = check("", probe = u => if (u.port == 3838) Preflight.Probe.InUse else Preflight.Probe.Free)
      code shouldBe None
      lines should have size 1
      lines.head should startWith(
        "naogateway: warning: port 3838 (UDP on 0.0.0.0, the GameController's broadcasts) is in use")
    }

    "list every port the demo binds, with the setting of each" in {
      val c = Launcher.nodeConfig(ConfigFactory.empty(), ConfigFactory.empty())
      Preflight.ports(c).map(u => (u.port, u.setting.takeWhile(_ != ' '))) shouldBe Vector(
        25520 -> "robotmiddleware.cluster.gateway-port",
        11019 -> "apps.control.bind",
        5555 -> "apps.zeromq.bind",
        5556 -> "apps.zeromq.publish",
        5557 -> "apps.datagram-door.port",
        8019 -> "apps.web.port",
        3838 -> "naogateway.game-controller.port"
      )
    }

    "say exactly what to do when the demo's robots lack their loopback addresses (macOS), and exit 2" in {
      val (lines, code) = check("", loopback = a => a.getHostAddress == "127.0.0.1")
      code shouldBe Some(Launcher.ExitConfig)
      lines shouldBe Vector(
        "naogateway: the demo's 3 simulated robots need loopback addresses of their own, and this machine lacks " +
          "127.0.0.11, 127.0.0.12, 127.0.0.13 (macOS has only 127.0.0.1): add them with " +
          "`for i in $(seq 11 13); do sudo ifconfig lo0 alias 127.0.0.$i up; done`, or run without simulated robots " +
          "(NAOGATEWAY_SIMULATED_ROBOTS=0)")
    }

    "pass the README's real-robot config and conf/robots.example.conf as they are: no key missing, none unknown" in {
      def find(relative: String): java.nio.file.Path =
        Seq(java.nio.file.Paths.get("../..", relative), java.nio.file.Paths.get(relative)).find(
          java.nio.file.Files.exists(_))
          .getOrElse(fail(s"$relative not found"))
      val readme =
        new String(java.nio.file.Files.readAllBytes(find("README.md")), java.nio.charset.StandardCharsets.UTF_8)
      val block = readme.split("```hocon\n", 2)(1).split("```", 2)(0)
      block should include("# robots.conf")
      // Without a signing key in the environment: the README's robots must not need one.
      check(block) shouldBe ((Vector.empty, None))
      val example =
        new String(java.nio.file.Files.readAllBytes(find("apps/launcher/src/universal/conf/robots.example.conf")),
          java.nio.charset.StandardCharsets.UTF_8)
      check(example) shouldBe ((Vector.empty, None))
    }

    "find the demo's loopback addresses on this machine (Linux routes all of 127.0.0.0/8)" in {
      assume(System.getProperty("os.name").toLowerCase.contains("linux"),
        "only Linux has every 127.x address by default")
      Preflight.missingLoopback(3) shouldBe None
    }
  }
}
