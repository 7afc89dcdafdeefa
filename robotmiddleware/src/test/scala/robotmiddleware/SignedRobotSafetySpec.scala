package robotmiddleware

import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.Await
import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.stream.scaladsl.Sink
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.api.{RobotOnline, RobotSnapshot}
import naogateway.integration.GatewayFixture
import naogateway.sim.network.ForgedFrames
import naogateway.sim.{ReceivedCall, SimulatedRobot}
import naogateway.testkit.TestLoopback
import naogateway.wire.{ActuatorGroup, Posture, SigningKey}

/** The issue's forged keep-alive, end to end through the middleware's battery safety: bursts of keep-alives claiming
  * 10.0 V from a robot's own address. Against a robot that signs, no app hears the reading and nothing stops or sits
  * it; against one that does not, the reading reaches the apps as the robot's (which is why signing exists). Loopback
  * only; generous timeouts.
  */
class SignedRobotSafetySpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {
  private val settings = MiddlewareSettings(10.8, 11.0, 200.millis, 2.seconds, 5.seconds, 1.second, 64)
  private val Patience = 30.seconds
  private val KeyHex = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f"
  private val Key = SigningKey.fromHex(KeyHex).toOption.get

  /** What the app heard and what the robot was sent after bursts of forged low-battery keep-alives. */
  private final case class Outcome(safetyStop: Option[AppEvent.SafetyStop], lowReading: Option[RobotSnapshot],
      sentAfter: Vector[String],
      posture: Posture)

  private def forge(signing: Boolean): Outcome = {
    val robotId = 51
    val ip = TestLoopback.address()
    val overrides =
      if (!signing) ""
      else s"""robots = [ { id = $robotId, address = "${ip.getHostAddress}", signing = required } ]
              |signing.key = "$KeyHex"""".stripMargin
    val f = new GatewayFixture(testKit, overrides)
    val outsider = DatagramChannel.open().bind(new InetSocketAddress(ip, 0))
    try {
      val (robot, _) = f.robot(robotId, firmware = fw => if (signing) fw.copy(signingKey = Some(Key)) else fw, at = ip)
      f.awaitEvent(Patience) { case RobotOnline(`robotId`, _) => () }
      val middleware = spawn(RobotMiddleware(f.gateway, settings))
      val app = Await.result(RobotClient.connect(system, middleware, "walker", 1), Patience)
      Await.result(app.acquire(robotId, ActuatorGroup.Walk), Patience)
      Await.result(app.posture(robotId, Posture.Stand), Patience) shouldBe Posture.Stand
      val stop =
        app.appEvents.collect { case e: AppEvent.SafetyStop => e }.takeWithin(6.seconds).runWith(Sink.headOption)
      val low =
        app.status(robotId).filter(_.batteryVoltage.exists(_ < 11.0)).takeWithin(6.seconds).runWith(Sink.headOption)
      val before = received(robot).size
      // Ten in a row beat the robot's own keep-alive every 200 ms: more than safety.battery-readings (5) low ones.
      val lie =
        ForgedFrames.unsigned(ForgedFrames.keepAlive(robotId, battery = 10.0, bootId = 1, posture = Posture.Stand))
      (1 to 3).foreach { _ =>
        (1 to 10).foreach(_ => outsider.send(ByteBuffer.wrap(lie), f.addresses.robots))
        Thread.sleep(300)
      }
      val heard = Await.result(stop, Patience)
      Outcome(heard, Await.result(low, Patience), received(robot).drop(before).map(_.call.name), f.view(robot).posture)
    } finally {
      outsider.close()
      f.stop()
    }
  }

  private def received(robot: akka.actor.typed.ActorRef[SimulatedRobot.Command]): Vector[ReceivedCall] = {
    val probe = createTestProbe[Vector[ReceivedCall]]()
    robot ! SimulatedRobot.GetReceivedCalls(probe.ref)
    probe.receiveMessage(10.seconds)
  }

  "Forged low-battery keep-alives from a robot's own address" must {
    "neither stop nor sit a robot that signs" in {
      val outcome = forge(signing = true)
      outcome.safetyStop shouldBe None
      outcome.lowReading shouldBe None
      outcome.sentAfter should not contain "motion.stop"
      outcome.sentAfter should not contain "motion.posture"
      outcome.posture shouldBe Posture.Stand
    }
    "reach the apps as the robot's reading when it does not sign (what signing protects against)" in {
      forge(signing = false).lowReading.flatMap(_.batteryVoltage) shouldBe Some(10.0)
    }
  }
}
