package naogateway.api

import java.io.File

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** The api module is plain data for apps: the build keeps Akka and the gateway off its classpath, and this spec fails
  * the day either comes back.
  */
class ApiLayerSpec extends AnyWordSpec with Matchers {

  private val loader = getClass.getClassLoader

  private def loadable(name: String): Boolean =
    try { Class.forName(name, false, loader); true }
    catch { case _: ClassNotFoundException => false }

  "The api module's classpath" should {
    "not hold Akka" in {
      loadable("akka.actor.typed.ActorSystem") shouldBe false
      val jars = System.getProperty("java.class.path").split(File.pathSeparator).toSeq.map(new File(_).getName)
      jars.filter(_.startsWith("akka-")) shouldBe empty
    }

    "not hold the gateway's actors" in {
      Seq(
        "naogateway.gateway.Gateway$",
        "naogateway.gateway.robot.RobotActor$",
        "naogateway.gateway.robot.Outbox$",
        "naogateway.gateway.robot.SessionRule",
        "naogateway.gateway.robot.KeepAliveStep"
      )
        .filter(loadable) shouldBe empty
    }

    "hold what apps see, in the gateway's packages, and the wire types it is built on" in {
      Seq(
        "naogateway.api.RobotSnapshot",
        "naogateway.api.RobotFailure",
        "naogateway.api.GatewayEvent",
        "naogateway.api.VisionFrame",
        "naogateway.api.LinkStats",
        "naogateway.api.ClockEstimate",
        "naogateway.api.TrafficStats",
        "naogateway.api.GatewayStats",
        "naogateway.api.GameSource",
        "naogateway.api.recording.RecordingStats",
        "naogateway.api.ReplayProgress",
        "naogateway.wire.Posture",
        "naogateway.wire.ActuatorGroup",
        "naogateway.wire.RpcValue"
      ).filterNot(loadable) shouldBe empty
    }
  }

  "A robot's snapshot" should {
    "take a keep-alive's report and keep its link fields (the data half of the keep-alive step)" in {
      val before =
        RobotSnapshot(7, new java.net.InetSocketAddress("127.0.0.1", 9000), batteryVoltage = Some(11.9), online = true)
      val status = naogateway.proto.Status(teamID = Some(3))
      val after = RobotSnapshot.afterKeepAlive(before, status, None, receivedAtNanos = 42L)
      after.teamId shouldBe Some(3)
      after.online shouldBe true
      after.address shouldBe before.address
      after.batteryVoltage shouldBe None
      after.receivedAtNanos shouldBe 42L
    }
  }
}
