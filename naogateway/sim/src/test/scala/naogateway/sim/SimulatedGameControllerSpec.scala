package naogateway.sim

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.wire.gamecontroller._

class SimulatedGameControllerSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {
  import SimulatedGameController._

  private val target = SimulatedRobotSettings.AnyLoopbackPort
  private val settings = SimulatedGameControllerSettings(target)

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
        val s = SimulatedGameControllerSettings(gateway.address, interval = 50.millis)
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
  }
}
