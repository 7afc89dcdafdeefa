package robotmiddleware

import scala.concurrent.duration._

import akka.Done
import akka.actor.testkit.typed.scaladsl.{ActorTestKit, LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.time.{Seconds, Span}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.api.RobotFailure
import naogateway.wire.ActuatorGroup

/** The facade fails every future with a `RobotFailure` (docs/writing-apps.md, Failures), and never throws. */
class RobotInterfaceSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  private def connected(): (RobotInterface, akka.actor.testkit.typed.scaladsl.TestProbe[RobotMiddleware.Command]) = {
    val middleware = createTestProbe[RobotMiddleware.Command]()
    val interface = RobotClient.connect(system, middleware.ref, "silent-test", timeout = 100.millis)
    middleware.expectMessageType[RobotMiddleware.RegisterApp].replyTo ! RobotMiddleware.AppRegistered("silent-test")
    (interface.futureValue, middleware)
  }

  "RobotInterface" should {
    "stream a player's GameController penalty from the game state: each change once, by name with the seconds left" in {
      import naogateway.wire.gamecontroller._
      val (interface, middleware) = connected()
      val seen = createTestProbe[Option[PlayerPenalty]]()
      interface.penalty(12, 3).runWith(akka.stream.scaladsl.Sink.foreach(seen.ref ! _))(
        akka.stream.Materializer(system))
      val games = middleware.expectMessageType[RobotMiddleware.WatchGame]
      val playing = GameControllerCodec.decodeControl(GameControllerVectors.bytes("v20-playing.bin")) match {
        case Right(d: Hsl20ControlData) => d
        case other                      => fail(s"v20-playing.bin: $other")
      }
      def player3(p: Hsl20PlayerInfo) =
        playing.copy(team0 = playing.team0.copy(players = playing.team0.players.updated(2, p)))
      val free = player3(Hsl20PlayerInfo.Unpenalised)
      Seq(free, playing, playing, player3(Hsl20PlayerInfo(Hsl20Penalty.Pushing, 24, 0)), free).foreach(
        games.subscriber ! _)
      seen.expectMessage(None)
      seen.expectMessage(Some(PlayerPenalty(Hsl20Penalty.Pushing, 25)))
      seen.expectMessage(Some(PlayerPenalty(Hsl20Penalty.Pushing, 24)))
      seen.expectMessage(None)
      seen.expectNoMessage(200.millis)
      PlayerPenalty(Hsl20Penalty.MotionInStop, 13).describe shouldBe "motion in stop, 13 s left"
    }
    "stream a robot's servo telemetry from its snapshots: each new one once, none while it has none" in {
      import naogateway.api.{RobotSnapshot, ServoReading, ServoReadings}
      val (interface, middleware) = connected()
      val seen = createTestProbe[ServoReadings]()
      interface.servos(2).runWith(akka.stream.scaladsl.Sink.foreach(seen.ref ! _))(akka.stream.Materializer(system))
      val watch = middleware.expectMessageType[RobotMiddleware.WatchStatus]
      watch.robotId shouldBe Some(2)
      val robot = RobotSnapshot(2, new java.net.InetSocketAddress("127.0.0.1", 3838), online = true)
      val first = ServoReadings(Vector(ServoReading(1, Some(512), Some(3), Some(12.0), Some(40))), Some(0L), 1L)
      val second = first.copy(receivedAtNanos = 2L)
      // Keep-alives without telemetry keep the last one in the snapshot: it is not emitted again.
      Seq(
        robot,
        robot.copy(servos = Some(first)),
        robot.copy(servos = Some(first)),
        robot.copy(servos = Some(second)),
        robot.copy(online = false),
        robot.copy(servos = Some(first))
      ).foreach(watch.subscriber ! _)
      seen.expectMessage(first)
      seen.expectMessage(second)
      seen.expectMessage(first) // after the robot went offline, the next telemetry is news again
      seen.expectNoMessage(200.millis)
      MiddlewareSettings(system).servoLimits shouldBe ServoLimits(65, 10.0)
      ServoLimits().hot(ServoReading(1, temperature = Some(65))) shouldBe true
      ServoLimits().hot(ServoReading(1, temperature = Some(64))) shouldBe false
      ServoLimits().lowVoltage(ServoReading(1, voltage = Some(9.9))) shouldBe true
      ServoLimits().lowVoltage(ServoReading(1, silent = true)) shouldBe false
    }

    "fail an operation the middleware never answers with RobotFailure.Timeout, not an ask timeout" in {
      val (interface, middleware) = connected()
      val stopped = interface.stop(4)
      middleware.expectMessageType[RobotMiddleware.Execute].robotId shouldBe 4
      // The ask waits the interface's timeout plus the 5 s margin for posture changes.
      val failure = stopped.failed.futureValue(timeout(Span(8, Seconds)))
      failure shouldBe a[RobotFailure.Timeout]
      failure.asInstanceOf[RobotFailure.Timeout].robotId shouldBe 4
    }

    "ask for a set of leases in one request, so the middleware grants all of them or none" in {
      val (interface, middleware) = connected()
      val acquired = interface.acquire(4, ActuatorGroup.Walk, ActuatorGroup.Head, ActuatorGroup.Walk)
      val request = middleware.expectMessageType[RobotMiddleware.Acquire]
      request.groups shouldBe Set[ActuatorGroup](ActuatorGroup.Walk, ActuatorGroup.Head)
      middleware.expectNoMessage(100.millis)
      request.replyTo ! RobotMiddleware.LeaseResult(4, request.groups,
        Left(RobotFailure.LeaseNotHeld(4, ActuatorGroup.Head, Some("referee"))))
      acquired.failed.futureValue shouldBe RobotFailure.LeaseNotHeld(4, ActuatorGroup.Head, Some("referee"))
    }

    "fail every kind of request the middleware never answers with RobotFailure.Timeout: list, lease, send, call" in {
      val (interface, middleware) = connected()
      val listed = interface.robots()
      middleware.expectMessageType[RobotMiddleware.ListRobots]
      val acquired = interface.acquire(4, ActuatorGroup.Head)
      middleware.expectMessageType[RobotMiddleware.Acquire]
      val sent = interface.send(4, "speech", "say", naogateway.wire.RpcValue.Text("hi"))
      middleware.expectMessageType[RobotMiddleware.Send].operation shouldBe Operation.RawCall("speech", "say",
        Vector(naogateway.wire.RpcValue.Text("hi")))
      val called = interface.call(4, "system", "battery")
      middleware.expectMessageType[RobotMiddleware.Execute]
      val waited = timeout(Span(8, Seconds))
      listed.failed.futureValue(waited) shouldBe a[RobotFailure.Timeout]
      acquired.failed.futureValue(waited) shouldBe a[RobotFailure.Timeout]
      sent.failed.futureValue(waited) shouldBe RobotFailure.Timeout(4, "speech.say", 5100)
      called.failed.futureValue(waited) shouldBe a[RobotFailure.Timeout]
    }

    "tell the app of a superseded or interrupted call as Overloaded, and pass every other failure as it is" in {
      val (interface, middleware) = connected()
      val head = interface.head(4, 0.1, 0.0)
      middleware.expectMessageType[RobotMiddleware.Execute].replyTo !
        naogateway.api.CallResult(4, "motion.head", Left(RobotFailure.Superseded(4, "motion.head")))
      head.failed.futureValue shouldBe RobotFailure.Overloaded(4, "motion.head replaced by a newer one")
      val ping = interface.call(4, "system", "ping")
      middleware.expectMessageType[RobotMiddleware.Execute].replyTo !
        naogateway.api.CallResult(4, "system.ping", Left(RobotFailure.Interrupted(4, "system.ping")))
      ping.failed.futureValue shouldBe RobotFailure.Overloaded(4, "system.ping interrupted, try again")
      val said = interface.say(4, "hi")
      middleware.expectMessageType[RobotMiddleware.Execute].replyTo !
        naogateway.api.CallResult(4, "speech.say", Left(RobotFailure.RobotError(4, "muted")))
      said.failed.futureValue shouldBe RobotFailure.RobotError(4, "muted")
    }

    "complete a send once the middleware accepted it, and fail it with the middleware's refusal" in {
      val (interface, middleware) = connected()
      val accepted = interface.send(4, Operation.Head(0.1, 0.0))
      val first = middleware.expectMessageType[RobotMiddleware.Send]
      first.operation shouldBe Operation.Head(0.1, 0.0)
      first.replyTo ! RobotMiddleware.SendResult(4, "motion.head", Right(()))
      accepted.futureValue shouldBe Done
      val refused = interface.send(4, Operation.Head(0.2, 0.0))
      middleware.expectMessageType[RobotMiddleware.Send].replyTo !
        RobotMiddleware.SendResult(4, "motion.head", Left(RobotFailure.SafetyHold(4, "battery low")))
      refused.failed.futureValue shouldBe RobotFailure.SafetyHold(4, "battery low")
    }

    "fail, never throw, when the app's actor system is gone" in {
      val gone = ActorTestKit("gone-app")
      val middleware = gone.createTestProbe[RobotMiddleware.Command]()
      val connecting = RobotClient.connect(gone.system, middleware.ref, "gone", timeout = 100.millis)
      middleware.expectMessageType[RobotMiddleware.RegisterApp].replyTo ! RobotMiddleware.AppRegistered("gone")
      val interface = connecting.futureValue
      gone.shutdownTestKit()
      val attempts = Seq(
        interface.stop(4),
        interface.send(4, "system", "battery"),
        interface.robots(),
        interface.acquire(4, ActuatorGroup.Walk),
        interface.call(4, "system", "battery")
      )
      attempts.foreach(_.failed.futureValue(timeout(Span(8, Seconds))) shouldBe a[RobotFailure])
    }

    "fail a connect the middleware never answers with RobotFailure.Timeout, and close the session made for it" in {
      val middleware = createTestProbe[RobotMiddleware.Command]()
      val connecting = RobotClient.connect(system, middleware.ref, "unanswered", timeout = 100.millis)
      val session = middleware.expectMessageType[RobotMiddleware.RegisterApp].events
      connecting.failed.futureValue shouldBe RobotFailure.Timeout(0, "connect", 100)
      createTestProbe[Any]().expectTerminated(session)
    }

    "fail a walk with velocities that are no numbers in the future, without sending it" in {
      val (interface, middleware) = connected()
      val walked = interface.walk(4, Double.NaN, 0.0, Double.PositiveInfinity)
      walked.failed.futureValue shouldBe RobotFailure.RobotError(4, "out of range: vx NaN, allowed finite numbers")
      middleware.expectNoMessage(100.millis)
    }
  }
}
