package naogateway.integration

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit, TestProbe}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.GatewayAccess
import naogateway.api.{GameStateUpdated, GatewayEvent, GatewayStats, RobotOffline, RobotOnline, RobotRestarted}
import naogateway.gateway.{Gateway, GatewaySettings}
import naogateway.gateway.link.Replay
import naogateway.sim.network.{Impairment, LossyNetwork}
import naogateway.sim.{SimulatedGameController, SimulatedGameControllerSettings, SimulatedRobot}
import naogateway.testkit.TestLoopback
import naogateway.testkit.TempFiles.withTempDir
import naogateway.wire.gamecontroller.GameState

/** Records a run (two simulated robots, one behind 10 % loss each way, one power-cycled, a GameController going through
  * a whole half), replays the recording into a fresh gateway without sockets, and compares what both told their
  * subscribers.
  */
class ReplaySpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  /** Robot events (online, offline, restarted) by robot, and the game states as they changed. */
  private final case class Story(robots: Map[Int, Vector[String]], game: Vector[GameState])

  private def story(events: Vector[GatewayEvent]): Story = {
    val robots = events.collect {
      case RobotOnline(id, _)       => id -> "online"
      case RobotOffline(id, _)      => id -> "offline"
      case RobotRestarted(id, _, _) => id -> "restarted"
    }.groupBy(_._1).map { case (id, es) => id -> es.map(_._2) }
    val states = events.collect { case GameStateUpdated(d) => d.gameState }
    Story(robots,
      states.foldLeft(Vector.empty[GameState])((acc, s) => if (acc.lastOption.contains(s)) acc else acc :+ s))
  }

  /** Everything `probe` got within `during`, or until what it got so far satisfies `enough`. */
  private def collect(probe: TestProbe[GatewayEvent], during: FiniteDuration)(
      enough: Vector[GatewayEvent] => Boolean = _ => false): Vector[GatewayEvent] = {
    val deadline = during.fromNow
    var got = Vector.empty[GatewayEvent]
    while (deadline.hasTimeLeft() && !enough(got)) {
      try got :+= probe.receiveMessage(deadline.timeLeft.max(1.milli))
      catch { case _: AssertionError => () } // nothing more within the time
    }
    got
  }

  "A replayed recording" must {
    "tell the gateway's subscribers the same robot events and game states as the run it was recorded from" in {
      withTempDir("replay-spec") { dir =>
        val network = LossyNetwork.start(seed = 5)
        val f = new GatewayFixture(testKit, s"""recording { enabled = on, directory = "${dir.toString}" }""")
        val recorded =
          try {
            val lossy = Impairment(loss = 0.1)
            val proxy = network.addProxy(f.addresses.robots, TestLoopback.address(), uplink = lossy, downlink = lossy)
            f.robot(1, to = proxy.clientSide)
            val (two, _) = f.robot(2)
            val gc = spawn(SimulatedGameController(SimulatedGameControllerSettings(f.addresses.gameController.get,
                  initial = 500.millis, ready = 700.millis, set = 500.millis, playing = 2.seconds,
                  finished = 700.millis,
                  interval = 100.millis)))
            val first = collect(f.events, 2.seconds)()
            two ! SimulatedRobot.PowerCycle(1500.millis)
            // The run is over once the game finished and robot 2 came back: the recording need not be longer.
            val rest = collect(f.events, 7.seconds) { got =>
              val s = story(first ++ got)
              s.game.contains(GameState.Finished) && s.robots.get(2).exists(_.contains("restarted"))
            }
            testKit.stop(gc)
            first ++ rest
          } finally {
            f.stop()
            network.stop()
          }
        val original = story(recorded)
        // The run itself must hold what the replay is to show.
        original.robots.keySet shouldBe Set(1, 2)
        original.robots(2) should contain("restarted")
        original.game should contain allOf (GameState.Initial, GameState.Ready, GameState.Set, GameState.Playing,
          GameState.Finished)

        val settings = GatewaySettings.fromConfig(com.typesafe.config.ConfigFactory.load().getConfig("naogateway"))
        val replaying = spawn(Gateway(settings, Some(Replay.of(dir, speed = 1.0))))
        val events = createTestProbe[GatewayEvent]()
        replaying ! GatewayAccess.Subscribe(events.ref)
        val stats = createTestProbe[GatewayStats]()
        val replayed = Vector.newBuilder[GatewayEvent]
        var finished = false
        val deadline = 40.seconds.fromNow
        while (!finished && deadline.hasTimeLeft()) {
          replayed ++= collect(events, 500.millis)()
          replaying ! GatewayAccess.GetStats(stats.ref)
          val s = stats.receiveMessage(5.seconds)
          finished = s.replay.exists(_.finished)
          if (finished) {
            s.replay.get.fed should be > 0L
            // What the replaying gateway sent (option pulls, probes) went nowhere, but was counted.
            s.replay.get.discarded should be > 0L
          }
        }
        finished shouldBe true
        testKit.stop(replaying)
        val again = story(replayed.result())
        withClue(s"recorded: $original\nreplayed: $again\n") {
          again.game shouldBe original.game
          original.robots.foreach { case (id, sequence) =>
            // The recording ends where the run did: the replay may go on to see the robots fall silent afterwards.
            again.robots.getOrElse(id, Vector.empty).take(sequence.size) shouldBe sequence
            again.robots.getOrElse(id, Vector.empty).drop(sequence.size).toSet should (be(empty) or be(Set("offline")))
          }
        }
      }
    }
  }
}
