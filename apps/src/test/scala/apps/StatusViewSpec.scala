package apps

import java.net.InetSocketAddress

import org.scalacheck.{Arbitrary, Gen}
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.wire.gamecontroller.{
  ControlData2014,
  GameControlData,
  GameControllerCodec,
  GameControllerGenerators,
  GameState,
  SecondaryGameState
}
import naogateway.wire.Posture
import naogateway.api.{LinkQuality, LinkStats, RobotSnapshot, SigningState, TrafficStats}

class StatusViewSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {
  import StatusViewSpec._

  private val address = new InetSocketAddress("127.0.0.1", 40000)
  private val sitting =
    RobotSnapshot(1, address, role = Some("keeper"), posture = Some(Posture.Sit), batteryVoltage = Some(12.4),
      online = true, quality = LinkQuality.Good)
  private val link = LinkStats(1, 10, 10, 300, 300, Some(0.4), 0.0, 0, Map.empty)
  private val traffic =
    TrafficStats(1500, 500, 125000, Map.empty, 10, 10, 0, 0, gameRunning = false, competition = false)

  private def game(file: String): GameControlData =
    GameControllerCodec.decodeControl(vector(file)).fold(e => fail(s"$file does not decode: ${e.describe}"), identity)

  "The status view" should {
    "show each robot's id, online state, link quality, battery, posture, role, round-trip time, loss and address" in {
      val line = StatusView.robotLine(sitting, Some(link.copy(lossEstimate = 0.25)))
      Seq("robot 1", "online", "good", "12.40 V", "sit", "keeper", "0.4 ms", "25 %", "127.0.0.1:40000").foreach(
        line should include(_))
    }
    "print one plain line per robot and change of online state or posture, and nothing when nothing changed" in {
      val first = StatusModel(Vector(sitting), Map(1 -> link), None, None)
      StatusView.changes(StatusModel.empty, first).map(_.take(20)) shouldBe Vector("robot 1   online  go")
      StatusView.changes(first, first) shouldBe empty
      val standing = first.copy(robots = Vector(sitting.copy(posture = Some(Posture.Stand))))
      StatusView.changes(first, standing).head should include("stand")
      val offline = first.copy(robots = Vector(sitting.copy(online = false)))
      StatusView.changes(first, offline).head should include("offline")
    }
    "show a robot that must sign and does not as unsigned, not offline, and a development build beside the robot" in {
      val unsigned = sitting.copy(online = false, quality = LinkQuality.Offline, signing = SigningState.Unsigned)
      StatusView.robotLine(unsigned, None) should (include("unsigned") and not include "offline")
      StatusView.robotLine(sitting.copy(online = false), None) should include("offline")
      StatusView.robotLine(sitting, None) should not include "development"
      StatusView.robotLine(sitting.copy(development = true), None) should include("development build")
      val first = StatusModel(Vector(sitting.copy(online = false)), Map.empty, None, None)
      StatusView.changes(first, first.copy(robots = Vector(unsigned))).head should include("unsigned")
      StatusView.changes(StatusModel.empty, first.copy(robots = Vector(unsigned))).head should include("unsigned")
    }
    "show the recording's figures or the replay's progress on the screen, and nothing when neither runs" in {
      val plain = naogateway.api.GatewayStats(10, 0, 0, Map.empty, 1)
      StatusView.recordingLine(None) shouldBe None
      StatusView.recordingLine(Some(plain)) shouldBe None
      val recording = plain.copy(recording = naogateway.api.recording.RecordingStats(enabled = true, 2, 1234, 5, 0,
        Some("/var/naogateway/recordings/naogateway-20260101-120000-2.mcap")))
      StatusView.recordingLine(Some(recording)) shouldBe
        Some("recording: 1234 messages in 2 file(s), 5 dropped, now naogateway-20260101-120000-2.mcap")
      val replay = plain.copy(replay = Some(naogateway.api.ReplayProgress(300, 7, finished = true)))
      StatusView.recordingLine(Some(replay)) shouldBe Some("replay: 300 datagrams fed, 7 outbound discarded, finished")
      StatusView.render(StatusModel.empty.copy(gateway = Some(recording))) should contain(
        "recording: 1234 messages in 2 file(s), 5 dropped, now naogateway-20260101-120000-2.mcap")
      // The tap's readers: named only when one fell behind, beside the recording or alone.
      val feed = naogateway.api.recording.TapReaderStats("foxglove-feed", 100, 12)
      val keeping = naogateway.api.recording.TapReaderStats("recorder", 1234, 0)
      StatusView.recordingLine(Some(plain.copy(tap = Vector(keeping)))) shouldBe None
      StatusView.recordingLine(Some(plain.copy(tap = Vector(keeping, feed)))) shouldBe
        Some("tap: foxglove-feed dropped 12")
      StatusView.recordingLine(Some(recording.copy(tap = Vector(keeping, feed)))) shouldBe
        Some("recording: 1234 messages in 2 file(s), 5 dropped, now naogateway-20260101-120000-2.mcap; " +
          "foxglove-feed dropped 12")
    }
    "show what the recording directory keeps and what retention deleted" in {
      val kept =
        naogateway.api.recording.RetentionStatus(12, 96L * 1024 * 1024, 3, 30L * 1024 * 1024, "20.0 GiB, 14 days", None)
      val stats = naogateway.api.GatewayStats(10, 0, 0, Map.empty, 1).copy(recording =
        naogateway.api.recording.RecordingStats(enabled = true, 2, 1234, 0, 0,
          Some("recordings/naogateway-20260101-120000-2.mcap"), Some(kept)))
      StatusView.recordingLine(Some(stats)) shouldBe Some("recording: 1234 messages in 2 file(s), 0 dropped, now " +
        "naogateway-20260101-120000-2.mcap; kept 12 file(s), 96.0 MiB (limits 20.0 GiB, 14 days); 3 deleted so far")
    }

    "render a screen with the game, the competition gate and the team's traffic against the budget" in {
      val screen = StatusView.render(StatusModel(Vector(sitting), Map.empty, Some(traffic), None))
      screen.head shouldBe "naogateway - 1 robot(s), 1 online"
      screen should contain("game: no GameController heard")
      screen should contain("competition gate: open (competition rule off)")
      screen should contain("team traffic: out 1.5 kB/s, in 0.5 kB/s, 2 % of the 125.0 kB/s budget")
      screen.exists(_.startsWith("robot 1")) shouldBe true
    }
    "render each real GameController packet on the screen: state, half, seconds left, secondary clock, score" in {
      def gameLine(file: String) = StatusView.render(StatusModel(Vector.empty, Map.empty, None, Some(game(file))))(1)
      gameLine(
        "v8-playing.bin") shouldBe "game: PLAYING, first half, 587 s left, score 2 : 1 (team 12 : team 7), version 8"
      gameLine(
        "v7-playing.bin") shouldBe "game: PLAYING, first half, 587 s left, score 2 : 1 (team 12 : team 7), version 7"
      gameLine(
        "v8-ready.bin") shouldBe "game: READY, first half, 600 s left, secondary 30 s, score 0 : 0 (team 12 : team 7), version 8"
      gameLine("v8-set.bin") should startWith("game: SET, first half, 600 s left, score")
      gameLine("v8-initial.bin") should startWith("game: INITIAL, first half, 600 s left")
      gameLine("v7-initial.bin") should startWith("game: INITIAL, first half, 600 s left")
      gameLine(
        "v8-finished.bin") shouldBe "game: FINISHED, second half, 587 s left, score 2 : 1 (team 12 : team 7), version 8"
      gameLine(
        "v19-playing.bin") shouldBe "game: PLAYING (goal kick, stopped), first half, 587 s left, secondary 30 s, score 2 : 1 " +
        "(team 12 : team 7), version 19"
      gameLine(
        "v19-ready.bin") shouldBe "game: READY, first half, 600 s left, secondary 45 s, score 0 : 0 (team 12 : team 7), version 19"
      gameLine(
        "v12-playing.bin") shouldBe "game: PLAYING (direct free kick), first half, 587 s left, score 2 : 1 (team 12 : team 7), version 12"
      gameLine(
        "v12-finished.bin") shouldBe "game: FINISHED, second half, 0 s left, score 2 : 1 (team 12 : team 7), version 12"
    }
    "print a line for each change of game state from the real packets, and none for a repeated state" in {
      val files =
        Seq("v8-initial.bin", "v7-initial.bin", "v8-ready.bin", "v8-set.bin", "v8-playing.bin", "v7-playing.bin",
          "v8-finished.bin")
      val models = StatusModel.empty +: files.map(f => StatusModel.empty.copy(game = Some(game(f))))
      val lines = models.zip(models.tail).flatMap { case (a, b) => StatusView.changes(a, b) }
      lines.map(_.takeWhile(_ != ',')) shouldBe Vector("game: INITIAL", "game: READY", "game: SET", "game: PLAYING",
        "game: FINISHED")
      lines(3) should include("587 s left, score 2 : 1")
    }
    "show the competition gate closing while the game runs, and print a line when it closes and opens" in {
      val open = traffic.copy(competition = true)
      val closed = open.copy(gameRunning = true)
      StatusView.gateLine(
        Some(closed)) shouldBe "competition gate: CLOSED: the game is running: nothing is sent to the robots"
      val unreadable = closed.copy(
        gateReason = Some("the trusted GameController's packet cannot be read: RGme packet of unknown version"))
      StatusView.gateLine(
        Some(unreadable)) shouldBe "competition gate: CLOSED: the trusted GameController's packet cannot be " +
        "read: RGme packet of unknown version: nothing is sent to the robots"
      StatusView.changes(StatusModel.empty.copy(traffic = Some(closed)),
        StatusModel.empty.copy(traffic = Some(unreadable))) shouldBe
        Vector(StatusView.gateLine(Some(unreadable)))
      StatusView.gateLine(Some(open)) shouldBe "competition gate: open"
      val models = Seq(None, Some(open), Some(open), Some(closed), Some(closed), Some(open)).map(t =>
        StatusModel.empty.copy(traffic = t))
      models.zip(models.tail).flatMap { case (a, b) => StatusView.changes(a, b) } shouldBe
        Vector(StatusView.gateLine(Some(open)), StatusView.gateLine(Some(closed)), StatusView.gateLine(Some(open)))
      // Without the rule the gate never closes, and the piped view says nothing about it.
      val off = Seq(None, Some(traffic),
        Some(traffic.copy(gameRunning = true, gateReason = Some("the game is running (Ready)"))))
        .map(t => StatusModel.empty.copy(traffic = t))
      off.zip(off.tail).flatMap { case (a, b) => StatusView.changes(a, b) } shouldBe empty
    }
    "print one line per change of the gate's reason, not one per packet: its figures and forged flips are no news" in {
      val playing = traffic.copy(competition = true, gameRunning = true,
        gateReason = Some("the game is running (Playing)"))
      val opening = playing.copy(gateReason =
        Some("opening once the game has not run for a while (Initial, 3 s more, 1 contradiction(s) so far)"))
      def unreadable(n: Int) = playing.copy(gateReason =
        Some(s"the trusted GameController's packet cannot be read (RGme of unknown version 14, 200 bytes; $n so far)"))
      val seen = Seq(playing, opening, playing, opening, playing) ++ (1 to 20).map(unreadable) :+
        traffic.copy(competition = true)
      val models = (None +: seen.map(Some(_))).map(t => StatusModel.empty.copy(traffic = t))
      models.zip(models.tail).flatMap { case (a, b) => StatusView.changes(a, b) } shouldBe Vector(
        StatusView.gateLine(Some(playing)),
        StatusView.gateLine(Some(unreadable(1))),
        "competition gate: open"
      )
      StatusView.gateLine(Some(unreadable(1))) should include("(RGme of unknown version 14, 200 bytes; 1 so far)")
    }
    "show a robot the GameController penalised beside it, by name with the seconds left, and print a line when it is" in {
      def game(file: String) = naogateway.wire.gamecontroller.GameControllerCodec.decodeControl(
        StatusViewSpec.vector(file)).toOption
      // v20-playing.bin: player 3 of team 12 pushed, 25 s left; v20-penalties.bin: player 4 moved while play stopped.
      val three = sitting.copy(robotId = 3, teamId = Some(12))
      val four = sitting.copy(robotId = 4, teamId = Some(12))
      StatusView.robotLine(three, None, game("v20-playing.bin")) should endWith(" PENALISED: pushing, 25 s left")
      StatusView.robotLine(four, None, game("v20-penalties.bin")) should endWith(
        " PENALISED: motion in stop, 13 s left")
      StatusView.robotLine(three.copy(robotId = 12), None, game("v20-penalties.bin")) should endWith(
        " PENALISED: cautioned, 21 s left")
      StatusView.robotLine(four, None, game("v20-playing.bin")) should not include "PENALISED"
      StatusView.robotLine(three.copy(teamId = Some(7)), None, game("v20-playing.bin")) should not include "PENALISED"
      StatusView.robotLine(three.copy(teamId = None), None, game("v20-playing.bin")) should not include "PENALISED"
      StatusView.robotLine(three, None, game("v19-playing.bin")) should endWith(" PENALISED: pushing, 25 s left")
      StatusView.render(StatusModel(Vector(three), Map.empty, None, game("v20-playing.bin"))).exists(
        _.endsWith("PENALISED: pushing, 25 s left")) shouldBe true
      // The line view: one line when the penalty starts and one when it ends, none as its clock counts down.
      val playing = game("v20-playing.bin").collect { case d: naogateway.wire.gamecontroller.Hsl20ControlData => d }.get
      def left(secs: Int) = playing.copy(team0 = playing.team0.copy(players =
        playing.team0.players.updated(2, playing.team0.players(2).copy(secsTillUnpenalised = secs))))
      val free = playing.copy(team0 = playing.team0.copy(players = playing.team0.players.updated(2,
        naogateway.wire.gamecontroller.Hsl20PlayerInfo.Unpenalised)))
      val models = Seq(free, left(25), left(24), left(23), free).map(g =>
        StatusModel(Vector(three), Map.empty, None, Some(g)))
      val lines = models.zip(models.tail).flatMap { case (a, b) => StatusView.changes(a, b) }
        .filter(_.startsWith("robot"))
      lines.size shouldBe 2
      lines.head should endWith("PENALISED: pushing, 25 s left")
      lines(1) should not include "PENALISED"
    }
    "show the message budget and the warnings on the screen, and print a warning line when one first appears" in {
      val quiet = naogateway.api.GameSource("127.0.0.1/32", None, 0,
        Some("team messages (team 12, UDP 10012): 12000 of 12000 left"))
      val twoGcs = quiet.copy(warnings = Vector(
        "2 GameControllers on this field: game state from 127.0.0.1:3838 only; 127.0.0.2:3838 (untrusted, ignored)"))
      val screen = StatusView.render(StatusModel.empty.copy(gameSource = Some(twoGcs)))
      screen should contain("team messages (team 12, UDP 10012): 12000 of 12000 left")
      screen should contain("WARNING: " + twoGcs.warnings.head)
      val models = Seq(quiet, twoGcs, twoGcs.copy(warnings = Vector(twoGcs.warnings.head + " ")), quiet)
        .map(g => StatusModel.empty.copy(gameSource = Some(g)))
      models.zip(models.tail).flatMap { case (a, b) => StatusView.changes(a, b) } shouldBe Vector(
        "WARNING: " + twoGcs.warnings.head)
    }
    "show, in the monitor role, the true state's age and each forwarded robot status beside the robot lines" in {
      val status =
        naogateway.wire.gamecontroller.ReturnStatus(3, 12, fallen = true, (1000f, -500f, 1.5f), 2f, (250f, -100f))
      val source = naogateway.api.GameSource(
        "127.0.0.1/32",
        None,
        0,
        trueStateAgeMillis = Some(400),
        forwarded = Vector(
          naogateway.api.ForwardedStatus(java.net.InetAddress.getByName("10.0.0.23"), status, 0L),
          naogateway.api.ForwardedStatus(java.net.InetAddress.getByName("10.0.0.24"),
            status.copy(player = 4, fallen = false, ballAge = -1f), 0L)
        )
      )
      StatusView.monitorLines(source) shouldBe Vector(
        "true game state from the GameController (monitor), 0.4 s old",
        "GameController hears team 12 player 3 (10.0.0.23): fallen, pose 1000 -500 mm 1.50 rad, ball seen 2.0 s ago",
        "GameController hears team 12 player 4 (10.0.0.24): up, pose 1000 -500 mm 1.50 rad, ball never seen"
      )
      val screen = StatusView.render(StatusModel(Vector(sitting), Map.empty, None, None, Some(source)))
      val robot = screen.indexWhere(_.startsWith("robot 1"))
      screen.slice(robot + 1, robot + 4) shouldBe StatusView.monitorLines(source)
    }
    "fit a screen into the terminal: lines cut to its width, the rows that do not fit counted" in {
      val lines = Vector("a" * 10, "b", "c", "d")
      StatusView.fit(lines, 4, 10) shouldBe Vector("aaaa", "b", "c", "d")
      StatusView.fit(lines, 80, 3) shouldBe Vector("a" * 10, "b", "... 2 more line(s); a taller terminal shows them")
      StatusView.fit(lines, 0, 0) shouldBe empty
    }
    "render, list changes and fit any model without throwing" in {
      forAll(genModel, genModel, Gen.choose(-5, 300), Gen.choose(-5, 100)) { (a, b, columns, rows) =>
        val screen = StatusView.render(b)
        screen.size shouldBe b.robots.size + 7
        StatusView.fit(screen, columns, rows).size should be <= math.max(rows, 0)
        StatusView.changes(a, b).size should be <= b.robots.size + 2
      }
    }
  }
}

object StatusViewSpec {

  /** The real GameController packet `file` of the test resources. */
  def vector(file: String): Array[Byte] = naogateway.wire.gamecontroller.GameControllerVectors.bytes(file)

  private val vectors = Seq("v8-initial.bin", "v7-initial.bin", "v8-ready.bin", "v8-set.bin", "v8-playing.bin",
    "v7-playing.bin", "v8-finished.bin")

  private val genDouble: Gen[Double] =
    Gen.oneOf(Gen.choose(-1e9, 1e9), Gen.oneOf(Double.NaN, Double.PositiveInfinity, Double.NegativeInfinity, 0.0))

  private val genAddress: Gen[InetSocketAddress] = Gen.oneOf(
    Gen.choose(0, 65535).map(new InetSocketAddress("127.0.0.1", _)),
    Gen.choose(0, 65535).map(InetSocketAddress.createUnresolved("robot.invalid", _)),
    Gen.const(null)
  )

  private val genRobot: Gen[RobotSnapshot] = for {
    id <- Arbitrary.arbitrary[Int]
    address <- genAddress
    role <- Gen.option(Arbitrary.arbitrary[String])
    posture <- Gen.option(Arbitrary.arbitrary[String].map(Posture.reported))
    battery <- Gen.option(genDouble)
    online <- Arbitrary.arbitrary[Boolean]
    quality <- Gen.oneOf(LinkQuality.Good, LinkQuality.Degraded, LinkQuality.Offline)
  } yield RobotSnapshot(id, address, role = role, posture = posture, batteryVoltage = battery, online = online, quality = quality)

  private def genLink(robotId: Int): Gen[LinkStats] = for {
    rtt <- Gen.option(genDouble)
    loss <- genDouble
  } yield LinkStats(robotId, 0, 0, 0, 0, rtt, loss, 0, Map.empty)

  private val genTraffic: Gen[TrafficStats] = for {
    out <- Arbitrary.arbitrary[Long]
    in <- Arbitrary.arbitrary[Long]
    budget <- Gen.oneOf(Gen.const(0), Arbitrary.arbitrary[Int])
    refused <- Arbitrary.arbitrary[Long]
    dropped <- Arbitrary.arbitrary[Long]
    running <- Arbitrary.arbitrary[Boolean]
    competition <- Arbitrary.arbitrary[Boolean]
    reason <- Gen.option(Gen.alphaStr)
  } yield TrafficStats(out, in, budget, Map.empty, 0, 0, refused, dropped, running, competition, reason)

  /** A real packet with arbitrary values in the fields the view shows. */
  private val gen2014: Gen[GameControlData] = for {
    file <- Gen.oneOf(vectors)
    state <- Gen.choose(0, 255)
    secondaryState <- Gen.choose(0, 255)
    secs <- Arbitrary.arbitrary[Long]
    secondary <- Gen.option(Arbitrary.arbitrary[Int])
    firstHalf <- Arbitrary.arbitrary[Boolean]
    score0 <- Arbitrary.arbitrary[Int]
    score1 <- Arbitrary.arbitrary[Int]
  } yield {
    val g = GameControllerCodec.decodeControl(vector(file)) match {
      case Right(d: ControlData2014) => d
      case other                     => throw new IllegalStateException(s"$file: $other")
    }
    g.copy(
      gameState = GameState.fromCode(state),
      secondaryGameState = SecondaryGameState.fromCode(secondaryState),
      secsRemaining = secs,
      secondaryTime = secondary,
      firstHalf = firstHalf,
      team0 = g.team0.copy(score = score0),
      team1 = g.team1.copy(score = score1)
    )
  }

  /** The 2014 vectors with arbitrary values where the view reads them, or any value of versions 19 and 12. */
  private val genGame: Gen[GameControlData] =
    Gen.oneOf(gen2014, GameControllerGenerators.controlV20, GameControllerGenerators.controlV19,
      GameControllerGenerators.controlV12)

  val genModel: Gen[StatusModel] = for {
    robots <- Gen.choose(0, 12).flatMap(Gen.listOfN(_, genRobot))
    links <- Gen.sequence[List[LinkStats], LinkStats](robots.take(6).map(r => genLink(r.robotId)))
    traffic <- Gen.option(genTraffic)
    game <- Gen.option(genGame)
  } yield StatusModel(robots.toVector, links.map(l => l.robotId -> l).toMap, traffic, game)
}
