package naogateway.sim

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.wire.gamecontroller._

class SimulatedGameControllerSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {
  import SimulatedGameController._

  private val target = SimulatedRobotSettings.AnyLoopbackPort
  // The 2014 GameController's rounds (a version-8 and a version-7 packet); versions 19 and 12 below.
  private val settings = SimulatedGameControllerSettings(target, version = GameControlVersion.V8)

  private def vector(file: String): Array[Byte] = GameControllerVectors.bytes(file)

  private def decode(bytes: Array[Byte]): ControlData2014 =
    GameControllerCodec.decodeControl(bytes) match {
      case Right(d: ControlData2014) => d
      case other                     => fail(s"not a 2014 packet: $other")
    }

  // The vectors' PLAYING and FINISHED packets carry a score and a penalty; the simulation plays 0 : 0 without fouls.
  private def withoutScoreAndFouls(d: ControlData2014): ControlData2014 = {
    def clean(t: TeamInfo) = t.copy(score = 0, players = Vector.fill(TeamInfo.PlayerSlots)(PlayerInfo.Unpenalised))
    d.copy(team0 = clean(d.team0), team1 = clean(d.team1))
  }

  private def momentOf(d: ControlData2014): GameMoment =
    GameMoment(d.gameState, d.firstHalf, d.kickOffTeam, d.secsRemaining, d.secondaryTime.getOrElse(0))

  "The simulated GameController's packets" should {
    "be byte-equal to the real packets for the same values" in {
      // (files of one moment, the moment's v8 packet number)
      val rounds = Seq(
        Seq("v8-initial.bin", "v7-initial.bin") -> 1,
        Seq("v8-ready.bin") -> 2,
        Seq("v8-set.bin") -> 3
      )
      rounds.foreach { case (files, number) =>
        val real = decode(vector(files.head))
        val ours = packets(settings, momentOf(real), number)
        ours.map(_.length) shouldBe Vector(158, 116)
        files.foreach { file =>
          val bytes = vector(file)
          withClue(file)(ours.find(_.length == bytes.length).map(_.toSeq) shouldBe Some(bytes.toSeq))
        }
      }
    }

    "match the real PLAYING and FINISHED packets in every field but the score and the fouls" in {
      Seq("v8-playing.bin" -> 4, "v7-playing.bin" -> 4, "v8-finished.bin" -> 5).foreach { case (file, number) =>
        val real = decode(vector(file))
        val ours = packets(settings, momentOf(real), number).map(decode).find(_.version == real.version)
        withClue(file)(ours shouldBe Some(withoutScoreAndFouls(real)))
      }
    }

    "decode in every state of the schedule as the real packet of that state does" in {
      val real = Map(
        GameState.Initial -> "v8-initial.bin",
        GameState.Ready -> "v8-ready.bin",
        GameState.Set -> "v8-set.bin",
        GameState.Playing -> "v8-playing.bin",
        GameState.Finished -> "v8-finished.bin"
      ).map { case (state, file) => state -> decode(vector(file)) }
      val realV7 = decode(vector("v7-initial.bin"))
      // Every 250 ms over two halves, so both halves and every state are seen.
      val seen = (0L until 2 * settings.halfNanos by 250000000L).map { t =>
        val moment = momentAt(settings, t)
        val Vector(v8, v7) = packets(settings, moment, (t / 250000000L).toInt).map(decode)
        val r = real(moment.gameState)
        // Every field but the clocks, the packet number, the half, the kick-off, the score and the fouls.
        def same(d: ControlData2014) = d.copy(packetNumber = r.packetNumber, secsRemaining = r.secsRemaining,
          secondaryTime = r.secondaryTime, firstHalf = r.firstHalf, kickOffTeam = r.kickOffTeam)
        same(v8) shouldBe withoutScoreAndFouls(r)
        v7.copy(gameState = GameState.Initial, secsRemaining = realV7.secsRemaining, firstHalf = true,
          kickOffTeam = KickOffTeam.Blue) shouldBe realV7
        v7.gameState shouldBe v8.gameState
        v7.secsRemaining shouldBe v8.secsRemaining
        moment.gameState
      }
      seen.distinct shouldBe Vector(GameState.Initial, GameState.Ready, GameState.Set, GameState.Playing,
        GameState.Finished)
    }
  }

  "The simulated GameController's schedule" should {
    "run INITIAL, READY, SET, PLAYING and FINISHED with the half's clock counting down only while PLAYING" in {
      val s = settings.copy(initial = 2.seconds, ready = 3.seconds, set = 1.second, playing = 10.seconds,
        finished = 2.seconds)
      def at(seconds: Double) = momentAt(s, (seconds * 1e9).toLong)
      at(0) shouldBe GameMoment(GameState.Initial, firstHalf = true, KickOffTeam.Blue, 10, 0)
      at(2) shouldBe GameMoment(GameState.Ready, firstHalf = true, KickOffTeam.Blue, 10, 3)
      at(3.5).secondaryTime shouldBe 2
      at(5) shouldBe GameMoment(GameState.Set, firstHalf = true, KickOffTeam.Blue, 10, 0)
      at(6) shouldBe GameMoment(GameState.Playing, firstHalf = true, KickOffTeam.Blue, 10, 0)
      at(6.5).secsRemaining shouldBe 10
      at(7).secsRemaining shouldBe 9
      at(15.9).secsRemaining shouldBe 1
      at(16) shouldBe GameMoment(GameState.Finished, firstHalf = true, KickOffTeam.Blue, 0, 0)
      // The second half: the other team kicks off; then the next game begins.
      at(18) shouldBe GameMoment(GameState.Initial, firstHalf = false, KickOffTeam.Red, 10, 0)
      at(34).gameState shouldBe GameState.Finished
      at(34).firstHalf shouldBe false
      at(36) shouldBe at(0)
    }
  }

  "A simulated GameController" should {
    "send a version-8 and a version-7 packet each round, the version-8 packet number counting up" in {
      val gateway = new TestGateway
      try {
        val s = SimulatedGameControllerSettings(gateway.address, interval = 50.millis, version = GameControlVersion.V8)
        val controller = spawn(SimulatedGameController(s))
        val heard = Iterator.continually(gateway.receive(5.seconds)).take(12).flatten.toVector
        testKit.stop(controller)
        heard should have size 12
        val decoded = heard.map(h => decode(h.bytes))
        decoded.map(_.version) shouldBe Vector.fill(6)(Vector(GameControlVersion.V8, GameControlVersion.V7)).flatten
        decoded.flatMap(_.packetNumber) shouldBe (1 to 6)
        all(decoded.map(_.gameState)) shouldBe GameState.Initial
      } finally gateway.close()
    }

    "send each round to every robot as well, as a broadcast reaches the field (docs/protocol.md 6.9)" in {
      val gateway = new TestGateway
      val robots = Vector.fill(2)(new TestGateway)
      try {
        val s = SimulatedGameControllerSettings(gateway.address, interval = 50.millis, robots = robots.map(_.address))
        val controller = spawn(SimulatedGameController(s))
        def three(at: TestGateway) =
          Iterator.continually(at.receive(5.seconds)).take(3).flatten.map(_.bytes.toVector).toVector
        val atGateway = three(gateway)
        val atRobots = robots.map(three)
        testKit.stop(controller)
        atGateway should have size 3
        atRobots.foreach(_ shouldBe atGateway)
      } finally (gateway +: robots).foreach(_.close())
    }
  }

  "The simulated GameController of versions 20, 19 and 12" should {
    val v20 = SimulatedGameControllerSettings(target, playersPerTeam = 7)
    val v19 = v20.copy(version = GameControlVersion.V19)
    val v12 = SimulatedGameControllerSettings(target, playersPerTeam = 4, version = GameControlVersion.V12)
    def one(s: SimulatedGameControllerSettings, moment: GameMoment, number: Int): Array[Byte] =
      packets(s, moment, number) match {
        case Vector(only) => only
        case other        => fail(s"${other.size} packets in a round of version ${s.version.number}")
      }
    val initial = GameMoment(GameState.Initial, firstHalf = true, KickOffTeam.Blue, 600, 0)

    "speak version 20 by default, one packet a round, byte-equal to the built vectors for the same values" in {
      SimulatedGameControllerSettings(target).version shouldBe GameControlVersion.V20
      one(v20, initial, 1).toSeq shouldBe vector("v20-initial.bin").toSeq
      one(v20, initial.copy(gameState = GameState.Ready, secondaryTime = 45), 2).toSeq shouldBe vector("v20-ready.bin").toSeq
      one(v20, initial.copy(gameState = GameState.Set), 3).toSeq shouldBe vector("v20-set.bin").toSeq
    }
    "speak version 19 when set, byte-equal to the built vectors for the same values" in {
      one(v19, initial, 1).toSeq shouldBe vector("v19-initial.bin").toSeq
      one(v19, initial.copy(gameState = GameState.Ready, secondaryTime = 45), 2).toSeq shouldBe vector("v19-ready.bin").toSeq
    }
    "speak version 12 when set, byte-equal to the built vectors for the same values" in {
      one(v12, initial, 1).toSeq shouldBe vector("v12-initial.bin").toSeq
      one(v12, initial.copy(gameState = GameState.Ready, secondaryTime = 30), 2).toSeq shouldBe vector("v12-ready.bin").toSeq
      one(v12, initial.copy(gameState = GameState.Set), 3).toSeq shouldBe vector("v12-set.bin").toSeq
      val v7only = packets(settings.copy(version = GameControlVersion.V7), initial, 1)
      v7only.map(_.toSeq) shouldBe Vector(vector("v7-initial.bin").toSeq)
    }
    "go through every state of both halves, with a stopped pause and a goal kick for teams[1] in PLAYING" in
      Seq(v20, v19).foreach { version =>
        val s =
          version.copy(initial = 1.second, ready = 1.second, set = 1.second, playing = 12.seconds, finished = 1.second,
            setPlayAfter = 4.seconds, stoppedFor = 2.seconds, setPlayFor = 3.seconds)
        val seen = (0L until 2 * s.halfNanos by 250000000L).map { t =>
          GameControllerCodec.decodeControl(one(s, momentAt(s, t), (t / 250000000L).toInt)) match {
            case Right(d: HslGameData) if d.version == version.version => d
            case other => fail(s"not version ${version.version.number}: $other")
          }
        }
        // Each step of the game once, in order (a state seen again later is a step again).
        val steps = seen.map(d => (d.gameState, d.stopped, d.setPlay, d.firstHalf))
          .foldLeft(Vector.empty[(GameState, Boolean, SetPlay, Boolean)])((acc, x) =>
            if (acc.lastOption.contains(x)) acc else acc :+ x)
        steps shouldBe Vector(
          (GameState.Initial, false, SetPlay.NoSetPlay, true),
          (GameState.Ready, false, SetPlay.NoSetPlay, true),
          (GameState.Set, false, SetPlay.NoSetPlay, true),
          (GameState.Playing, false, SetPlay.NoSetPlay, true),
          (GameState.Playing, true, SetPlay.GoalKick, true),
          (GameState.Playing, false, SetPlay.GoalKick, true),
          (GameState.Playing, false, SetPlay.NoSetPlay, true),
          (GameState.Finished, false, SetPlay.NoSetPlay, true),
          (GameState.Initial, false, SetPlay.NoSetPlay, false),
          (GameState.Ready, false, SetPlay.NoSetPlay, false),
          (GameState.Set, false, SetPlay.NoSetPlay, false),
          (GameState.Playing, false, SetPlay.NoSetPlay, false),
          (GameState.Playing, true, SetPlay.GoalKick, false),
          (GameState.Playing, false, SetPlay.GoalKick, false),
          (GameState.Playing, false, SetPlay.NoSetPlay, false),
          (GameState.Finished, false, SetPlay.NoSetPlay, false)
        )
        // The kicking team: team 12 kicks off the first half, team 7 the second, and team 7 takes the goal kick.
        seen.filter(d => d.firstHalf && d.setPlay == SetPlay.NoSetPlay).map(_.kickingTeam).distinct shouldBe Vector(
          Some(12))
        seen.filter(d => !d.firstHalf).map(_.kickingTeam).distinct shouldBe Vector(Some(7))
        seen.filter(_.setPlay == SetPlay.GoalKick).map(_.kickingTeam).distinct shouldBe Vector(Some(7))
        // The set play's countdown runs once play goes on; the half's clock runs throughout.
        val running = seen.filter(d => d.setPlay == SetPlay.GoalKick && !d.stopped)
        running.map(_.secondaryTime).distinct shouldBe Vector(3, 2, 1)
        val clocks = seen.filter(d => d.gameState == GameState.Playing && d.firstHalf).map(_.secsRemaining)
        clocks shouldBe clocks.sorted.reverse
        all(seen.map(_.team0.messageBudget)) shouldBe 12000
      }
    "say the set play in version 12 as its secondary state, with the taking team in secondaryStateInfo" in {
      val s = v12.copy(playing = 12.seconds, setPlayAfter = 4.seconds, stoppedFor = 2.seconds, setPlayFor = 3.seconds)
      val during = momentAt(s, (s.initial + s.ready + s.set + 5.seconds).toNanos)
      during.setPlay shouldBe SetPlay.GoalKick
      GameControllerCodec.decodeControl(one(s, during, 9)) match {
        case Right(d: HlControlData) =>
          d.secondaryState shouldBe HlSecondaryState.GoalKick
          d.secondaryStateInfo.head shouldBe 7.toByte
          d.kickOffTeam shouldBe Some(7)
        case other => fail(s"not version 12: $other")
      }
      // No set play where it does not fit PLAYING.
      val short = s.copy(playing = 8.seconds)
      short.hasSetPlay shouldBe false
      (0L until short.halfNanos by 250000000L).map(t => momentAt(short, t).setPlay).distinct shouldBe Vector(
        SetPlay.NoSetPlay)
    }
  }
}
