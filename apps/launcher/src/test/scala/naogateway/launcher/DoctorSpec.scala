package naogateway.launcher

import java.net.{DatagramSocket, InetSocketAddress, ServerSocket}
import java.nio.file.{Files, Paths}

import com.typesafe.config.ConfigFactory
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.launcher.Doctor.{Disk, Facts, GameSnapshot}
import naogateway.sim.{SimulatedGameController, SimulatedGameControllerSettings}
import naogateway.wire.gamecontroller.GameControlVersion
import naogateway.api.{ClockEstimate, GameSource, GatewayStats, LinkStats, RobotSnapshot, TrafficStats}
import naogateway.gateway.{GatewaySettings, Rejection}
import naogateway.testkit.TempFiles.withTempDir

/** `robotctl doctor`: each check finds the problem it names, provoked here, and stays quiet when all is well. */
class DoctorSpec extends AnyWordSpec with Matchers {

  private def settingsOf(naogatewayBlock: String): GatewaySettings =
    GatewaySettings.fromConfig(
      ConfigFactory.parseString(naogatewayBlock).withFallback(ConfigFactory.load()).getConfig("naogateway"))

  private val team =
    settingsOf("""naogateway.robots = [ { id = 1, address = "10.0.0.101" }, { id = 2, address = "10.0.0.102" } ]""")
  private def robot(id: Int, online: Boolean = true, heard: Boolean = true, clockBound: Double = 2.0) =
    RobotSnapshot(
      id,
      new InetSocketAddress(s"10.0.0.${100 + id}", 40000),
      online = online,
      receivedAtNanos = if (heard) 1L else 0L,
      clock = Some(ClockEstimate(1000, 2000000000L, 1.0, clockBound, 0.0, 100))
    )
  private def links(id: Int, rejected: Map[String, Long] = Map.empty) =
    LinkStats(id, 10, 10, 100, 100, Some(2.0), 0.0, 0, rejected)
  private val gcSettings = SimulatedGameControllerSettings(new InetSocketAddress("127.0.0.1", 3838))
  private val packet = SimulatedGameController.controlData(gcSettings, GameControlVersion.V8,
    SimulatedGameController.momentAt(gcSettings, 0L), 1)
  private val heardGame = GameSnapshot(Some(packet),
    GameSource("10.0.0.0/24", Some(new InetSocketAddress("10.0.0.5", 3838)), 0), Map.empty, competition = true)
  private val traffic =
    TrafficStats(2000, 3000, 125000, Map.empty, 100, 100, 0, 0, gameRunning = false, competition = true)
  private val stats = GatewayStats(100, 0, 10, Map.empty, 2)
  private val wellDisk = Disk(Paths.get("recordings"), writable = true, 100L * 1024 * 1024 * 1024)

  private val allWell =
    Facts(team, Vector(robot(1), robot(2)), Vector(links(1), links(2)), stats, Some(traffic), heardGame,
      Vector.empty, Some(wellDisk), None)

  private def problems(facts: Facts): Vector[String] = Doctor.findings(facts).filter(_.problem).map(_.line)

  "The doctor" should {
    "find nothing wrong with a team whose robots, GameController, budget, disk and config are fine" in {
      problems(allWell) shouldBe empty
      Doctor.findings(allWell).map(_.line) should contain("ok   robots: 2 of 2 known robot(s) online, 2 configured")
    }

    "find a tap reader that fell behind, and say nothing of one that kept up" in {
      val tap = Vector(naogateway.api.recording.TapReaderStats("recorder", 9000, 1000),
        naogateway.api.recording.TapReaderStats("foxglove-feed", 500, 0))
      problems(allWell.copy(stats = stats.copy(tap = tap))) shouldBe Vector(
        "FAIL tap: recorder fell behind and lost 1000 of 10000 entries; fix: raise naogateway.recording.queue-capacity, " +
          "record to a faster disk, or give the gateway's machine more room")
    }

    "find a GameController never heard, and a competition gate that cannot follow it" in {
      val p = problems(allWell.copy(game = heardGame.copy(latest = None)))
      p.exists(_.startsWith("FAIL GameController: no packet heard")) shouldBe true
      p.exists(_.startsWith("FAIL competition gate: on, but no game state yet")) shouldBe true
    }

    "find GameController packets from an untrusted source, naming the setting to fix" in {
      val p = problems(allWell.copy(game = heardGame.copy(source = heardGame.source.copy(untrusted = 12))))
      p should have size 1
      p.head should include("12 packet(s) from addresses not in trusted-sources")
      p.head should include("naogateway.game-controller.trusted-sources")
    }

    "warn of a GameController read by its shared header only, and of contradictions the competition gate counted" in {
      val later = "GameController version 21 (170 bytes) is not known to this gateway: only the header versions 18 " +
        "to 20 share is read (Playing), the teams and penalties are not; update naogateway (docs/protocol.md 10.12)"
      val forged = "competition gate: 7 contradiction(s) while it waited to open (a packet saying the game runs, ...)"
      val p = problems(allWell.copy(game = heardGame.copy(source = heardGame.source.copy(warnings =
          Vector(later, forged)))))
      p should have size 2
      p.head should startWith("FAIL GameController version: GameController version 21 (170 bytes) is not known")
      p.head should include("§10.12")
      p(1) should startWith("FAIL competition gate: competition gate: 7 contradiction(s)")
      p(1) should include("§10.7")
    }

    "find GameController packets the gateway cannot read (a version it does not know)" in {
      val p =
        problems(allWell.copy(game = heardGame.copy(refused = Map(Rejection.BadGameControllerPacket.name -> 40L))))
      p should have size 1
      p.head should startWith("FAIL GameController version: 40 packet(s) the gateway cannot read")
    }

    "name the versions the gateway reads and the fail-safe gate for a GameController it cannot read" in {
      val unreadable = heardGame.copy(
        latest = None,
        refused = Map(Rejection.BadGameControllerPacket.name -> 3L),
        gateReason = Some("the trusted GameController's packet cannot be read (RGme of unknown version 14, 200 bytes)")
      )
      val p = problems(allWell.copy(game = unreadable))
      p.exists(l =>
        l.startsWith("FAIL GameController version: 3 packet(s)") && l.contains("versions 20, 19, 12, 8, 7") && l.contains(
          "fail safe")) shouldBe true
      p should contain(
        "FAIL competition gate: on and closed: the trusted GameController's packet cannot be read (RGme of unknown " +
          "version 14, 200 bytes); " +
          "fix: see the GameController checks above")
    }

    "find a second GameController and the team's message budget running out, and show the budget" in {
      val warned = heardGame.copy(
        source = heardGame.source.copy(budget = Some("team messages (team 12, UDP 10012): 50 of 12000 left"),
          warnings = Vector("two GameControllers heard: 10.0.0.5 and 10.0.0.9")))
      val lines = Doctor.gameControllerFindings(warned).map(_.line)
      lines should contain("ok   team messages: team messages (team 12, UDP 10012): 50 of 12000 left")
      problems(allWell.copy(game = warned)).exists(
        _.startsWith("FAIL GameController: two GameControllers heard: 10.0.0.5 and 10.0.0.9")) shouldBe true
    }

    "say whether the competition gate is closed now, and why" in {
      val closed = heardGame.copy(gateReason = Some("the game is running (Playing)"))
      Doctor.gameControllerFindings(closed).last.line should endWith("closed now: the game is running (Playing)")
      Doctor.gameControllerFindings(heardGame).last.line should endWith("open now")
    }

    "report the GameController's version and state when heard" in {
      Doctor.gameControllerFindings(heardGame).head.line should startWith(
        "ok   GameController: heard, version 8, state ")
    }

    "find a robot configured but never heard, and one offline after being heard" in {
      val p = problems(allWell.copy(robots = Vector(robot(1, online = false, heard = false), robot(2, online = false))))
      p should contain allOf (
        "FAIL robot 1: configured at 10.0.0.101 but never heard; fix: switch it on; its firmware must send keep-alives to this " +
          "machine's UDP 11011 from 10.0.0.101 (README, \"With real robots\": when a robot does not come online)",
        "FAIL robot 2: offline (configured at 10.0.0.102, heard before); fix: check its battery and WiFi module; it must keep " +
          "sending keep-alives every 200 ms (robotctl status shows its loss)")
      // A configured robot the gateway has no actor for yet is never heard too.
      problems(allWell.copy(robots = Vector(robot(1)))).exists(
        _.startsWith("FAIL robot 2: configured at 10.0.0.102 but never heard")) shouldBe true
    }

    "find a robot heard but not configured, and frames claiming a robot's id from an unexpected address" in {
      val stranger = robot(7).copy(address = new InetSocketAddress("10.0.0.150", 40000))
      val mismatch =
        stats.copy(rejected = Map(Rejection.RobotIdMismatch.name -> 9L), rejectedBySource = Map("10.0.0.66" -> 9L))
      val p = problems(allWell.copy(robots = allWell.robots :+ stranger, stats = mismatch))
      p should contain(
        "FAIL robot 7: heard from 10.0.0.150 but not configured; fix: if it is yours, add { id = 7, address = \"10.0.0.150\" } " +
          "to naogateway.robots; if not, another team's robot sends here")
      p.exists(l =>
        l.startsWith("FAIL robot addresses: 9 frame(s) whose robot id belongs to another address") && l.contains(
          "10.0.0.66")) shouldBe true
    }

    "find a robot whose frames fail signature verification" in {
      val p = problems(allWell.copy(links = Vector(links(1, Map("unsigned" -> 30L, "bad signature" -> 2L)), links(2))))
      p should have size 1
      p.head should startWith("FAIL robot 1 signing: 32 frame(s) failed verification (bad signature 2, unsigned 30)")
    }

    "say which robots sign" in {
      val signed = settingsOf("naogateway.robots = [ { id = 1, address = \"10.0.0.101\" } ]\n" +
        "naogateway.signing.key = \"00112233445566778899aabbccddeeff\"")
      Doctor.signingFindings(allWell.copy(settings = signed)).head.line shouldBe
        "ok   signing: robot(s) 1 sign their frames with their robot keys; robots not configured must sign too"
      Doctor.signingFindings(allWell).head.line shouldBe "ok   signing: off: no team key (naogateway.signing.key)"
    }

    "in competition mode, find robots that do not sign, no team key, and development builds" in {
      val competition = "naogateway.competition.enabled = on\n" +
        "naogateway.game-controller.trusted-sources = [\"10.0.0.5\"]\n"
      val offRobot = settingsOf(competition +
        "naogateway.robots = [ { id = 1, address = \"10.0.0.101\" }, " +
        "{ id = 2, address = \"10.0.0.102\", signing = off } ]\n" +
        "naogateway.signing.key = \"00112233445566778899aabbccddeeff\"")
      val p = Doctor.signingFindings(allWell.copy(settings = offRobot)).filter(_.problem).map(_.line)
      p shouldBe Vector("FAIL robot 2 signing: signing = off in competition mode: anyone on the WiFi can command " +
        "this robot; fix: build the robot with its key (robotctl keys 2) and remove signing = off from its entry in " +
        "naogateway.robots")
      val keyless = settingsOf(competition + """naogateway.robots = [ { id = 1, address = "10.0.0.101" } ]""")
      Doctor.signingFindings(allWell.copy(settings = keyless)).filter(_.problem).map(_.line).head should startWith(
        "FAIL signing: competition mode without a team key")
      val development = allWell.copy(settings = offRobot, robots = Vector(robot(1).copy(development = true), robot(2)))
      Doctor.signingFindings(development).filter(_.problem).map(_.line) should contain(
        "FAIL robot 1 firmware: runs a development build: it neither signs nor checks signatures " +
          "(RobotHealth.development); fix: flash a field build with the robot's key (robotctl keys 1; docs/firmware.md)")
      // Outside competition mode a development robot is named, not a problem.
      val bench = allWell.copy(robots = Vector(robot(1).copy(development = true), robot(2)))
      problems(bench) shouldBe empty
      Doctor.signingFindings(bench).map(_.line) should contain(
        "ok   robot 1 firmware: runs a development build: it neither signs nor checks signatures " +
          "(RobotHealth.development)")
    }

    "find a clock estimate that does not converge" in {
      val p = problems(allWell.copy(robots = Vector(robot(1), robot(2, clockBound = 180.0))))
      p should have size 1
      p.head should startWith(
        "FAIL robot 2 clock: estimate does not converge (error bound ±180 ms over 100 keep-alives)")
      // A young estimate is wide by design and not judged yet.
      val young =
        robot(2, clockBound = 400.0).copy(clock = robot(2).clock.map(_.copy(errorBoundMillis = 400.0, samples = 12)))
      problems(allWell.copy(robots = Vector(robot(1), young))) shouldBe empty
    }

    "find the team's traffic near or over its budget" in {
      problems(allWell.copy(traffic = Some(traffic.copy(outBytesLastSecond = 110000)))).head should startWith(
        "FAIL team budget: 110000 B/s of 125000 B/s (88 %), 0 datagram(s) dropped")
      problems(allWell.copy(traffic = Some(traffic.copy(dropped = 4)))).head should include("4 datagram(s) dropped")
    }

    "find a recording directory that is not writable, a disk nearly full, and failing writes" in {
      problems(allWell.copy(disk = Some(wellDisk.copy(writable = false)))).head should startWith(
        "FAIL recording: recordings is not writable")
      problems(allWell.copy(disk = Some(wellDisk.copy(usableBytes = 300L * 1024 * 1024)))).head should startWith(
        "FAIL recording: 300.0 MiB free on the disk of recordings")
      val failing = stats.copy(recording = stats.recording.copy(enabled = true, failed = 7))
      problems(allWell.copy(stats = failing)).head should startWith(
        "FAIL recording writes: 7 entries could not be written")
    }

    "look at a real directory: writable here, not writable below a file" in {
      withTempDir("doctor-spec") { dir =>
        Doctor.disk(dir.resolve("recordings")).writable shouldBe true
        val file = Files.write(dir.resolve("a-file"), Array[Byte](1))
        Doctor.disk(file.resolve("recordings")).writable shouldBe false
      }
    }

    "find FU-Remote not listening where the relay sends, and see it when it listens" in {
      val relayed = allWell.copy(settings = team.copy(relay = Some(new InetSocketAddress("127.0.0.1", 11012))),
        fuRemoteListening = Some(false))
      problems(relayed).head should startWith("FAIL FU-Remote relay: nothing listens on UDP 127.0.0.1:11012")
      val fuRemote = new DatagramSocket(new InetSocketAddress("127.0.0.1", 0))
      try Doctor.listening(new InetSocketAddress("127.0.0.1", fuRemote.getLocalPort)) shouldBe Some(true)
      finally fuRemote.close()
    }

    "find config keys that are set but unknown (a typo)" in {
      val c = ConfigFactory.parseString("naogateway.recording.rotate-byte = 1MiB\napps.launcher.simulated-robots = 2")
      val keys = Preflight.unknownKeys(c, Preflight.knownKeys)
      keys shouldBe Vector("naogateway.recording.rotate-byte")
      problems(allWell.copy(unknownKeys = keys)) shouldBe Vector(
        "FAIL config: naogateway.recording.rotate-byte is not a setting and is ignored; fix: correct the typo (every key with its " +
          "default is in the reference.conf files)")
    }
  }

  "robotctl doctor without a running gateway" should {
    "say so first, then check the machine against the config file: keys, ports held by other programs, and exit 1" in {
      withTempDir("doctor-offline") { dir =>
        val held = new ServerSocket()
        held.bind(new InetSocketAddress("127.0.0.1", 0))
        val nothing = new ServerSocket(0)
        val closedPort = nothing.getLocalPort
        nothing.close()
        try {
          val file = Files.writeString(
            dir.resolve("robots.conf"),
            s"""apps.control.bind = "127.0.0.1:${held.getLocalPort}"
               |apps.zeromq.enabled = off
               |apps.datagram-door.enabled = off
               |apps.launcher.simulated-robots = 0
               |robotmiddleware.cluster.gateway-port = 0
               |naogateway.game-controller.enabled = off
               |naogateway.recording.directory = "${dir.resolve("rec")}"
               |naogateway.competiton.enabled = on
               |""".stripMargin
          )
          val out = Vector.newBuilder[String]
          val err = Vector.newBuilder[String]
          val code = RobotCtl.run(Seq("--control", s"127.0.0.1:$closedPort", "doctor", file.toString), _ => None,
            out += _, err += _)
          code shouldBe RobotCtl.ExitFailed
          val lines = out.result()
          lines.head shouldBe s"FAIL gateway: no gateway answers at 127.0.0.1:$closedPort; fix: start it (bin/naogateway $file), or give its control port with --control"
          lines should contain(
            "FAIL config: naogateway.competiton.enabled is not a setting and is ignored; fix: correct the typo (every key " +
              "with its default is in the reference.conf files)")
          lines should contain(
            s"FAIL ports: port ${held.getLocalPort} (TCP on 127.0.0.1, the control port robotctl talks to) is in use by " +
              "another program; fix: stop that program or move the port with apps.control.bind (NAOGATEWAY_CONTROL)")
          lines.exists(_.startsWith(s"ok   recording: ${dir.resolve("rec")} writable")) shouldBe true
          err.result() shouldBe Vector("robotctl: 3 problem(s), each with its fix above")
        } finally held.close()
      }
    }

    "name the key of a config that does not read" in {
      withTempDir("doctor-offline-bad") { dir =>
        val file = Files.writeString(dir.resolve("robots.conf"), "naogateway.link.robot-port = 70000\n")
        val out = Vector.newBuilder[String]
        RobotCtl.offlineDoctor("127.0.0.1:1", Some(file.toString), out += _, _ => ()) shouldBe RobotCtl.ExitFailed
        out.result() should contain("FAIL config: link.robot-port 70000 is not a UDP port; fix: correct the key named")
      }
    }
  }
}
