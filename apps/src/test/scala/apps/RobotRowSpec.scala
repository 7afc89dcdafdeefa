package apps

import java.net.InetSocketAddress

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.wire.Posture
import naogateway.api.{ClockEstimate, LinkQuality, LinkStats, RobotSnapshot, SigningState}

class RobotRowSpec extends AnyWordSpec with Matchers {

  private val address = new InetSocketAddress("127.0.0.1", 40000)
  private val clock = ClockEstimate(1000L, 5000000L, 1.00002, 0.7, 0.0, 12)
  private val robot = RobotSnapshot(
    3,
    address,
    teamId = Some(1),
    role = Some("keeper"),
    posture = Some(Posture.Sit),
    batteryVoltage = Some(12.4),
    uptimeMillis = Some(9000L),
    online = true,
    quality = LinkQuality.Degraded
  )
  private val link = LinkStats(3, 10, 10, 300, 300, Some(0.4), 0.25, 0, Map("bad gzip" -> 2L), Some(clock))

  "A robot's row" should {
    "take the robot's report from its snapshot and the link figures, with the link's clock estimate" in {
      val row = RobotRow.of(robot, Some(link))
      (row.robotId, row.address, row.online, row.quality) shouldBe ((3, Some("127.0.0.1:40000"), true,
        Some(LinkQuality.Degraded)))
      row.report shouldBe robot.report
      (row.battery, row.posture, row.rttMillis, row.loss, row.clock) shouldBe ((Some(12.4), Some(Posture.Sit),
        Some(0.4), Some(0.25), Some(clock)))
      row.refused shouldBe Map("bad gzip" -> 2L)
      RobotRow.of(robot.copy(clock = Some(clock)), None).clock shouldBe Some(clock)
    }

    "leave out what is missing or not finite, whatever the snapshot holds" in {
      val row = RobotRow.of(RobotSnapshot(4, null, batteryVoltage = Some(Double.NaN), quality = null),
        Some(link.copy(rttMillis = Some(Double.PositiveInfinity), lossEstimate = Double.NaN)))
      (row.address, row.quality, row.battery, row.rttMillis, row.loss) shouldBe ((None, None, None, None, None))
    }

    "show a robot that must sign and is heard only unsigned as unsigned, without a link quality, on both lines" in {
      val unsigned = robot.copy(online = false, quality = LinkQuality.Offline, signing = SigningState.Unsigned)
      val row = RobotRow.of(unsigned, None)
      (row.linkState, row.quality) shouldBe (("unsigned", None))
      RobotRow.of(robot.copy(online = false, quality = LinkQuality.Offline), None).linkState shouldBe "offline"
      // Online, a robot that signs is online whatever a stranger sent meanwhile.
      RobotRow.of(robot.copy(signing = SigningState.Signed), None).linkState shouldBe "online"
      control.ControlText.statusLine(unsigned, None).split("\\s+").toList.slice(2, 4) shouldBe
        List("unsigned", "-")
      StatusView.robotLine(unsigned, None) should include("unsigned")
      control.ControlText.statusLine(robot.copy(development = true), None) should endWith("development build")
      control.ControlText.statusLine(robot, None) should not include "development"
    }

    "be what the launcher's line, robotctl's line and the web card show alike" in {
      val row = RobotRow.of(robot, Some(link))
      val shown = Seq("127.0.0.1:40000", "degraded", "12.40 V", "sit", "keeper", "0.4 ms", "25 %")
      shown.foreach(StatusView.robotLine(robot, Some(link)) should include(_))
      shown.foreach(control.ControlText.statusLine(robot, Some(link)) should include(_))
      val card = web.WebJson.robot(robot, Some(link), None).fields
      (card("address").toString, card("battery").toString, card("posture").toString) shouldBe
        ((s"\"${row.address.get}\"", "12.4", "\"sit\""))
      control.ControlText.statusLine(robot, Some(link)) should include("±0.7 ms")
    }

    "show a robot's drift only once its bound has settled, as `settling` before" in {
      // Two seconds after a start: the drift is held at its limit, its bound twice that.
      val young = link.copy(clock = Some(ClockEstimate(1000L, 5000000L, 1.001, 3.0, 0.002, 10)))
      control.ControlText.statusLine(robot, Some(young)).split("\\s+").takeRight(4).toList shouldBe
        List("±3.0", "ms", "settling", "-")
      val card = web.WebJson.robot(robot, Some(young), None).fields("clock").asJsObject.fields
      (card("driftSettled").toString, card("driftBoundPpm").toString) shouldBe (("false", "2000.0"))
      val settled = link.copy(clock = Some(ClockEstimate(1000L, 5000000L, 1.0 / (1.0 + 35e-6), 0.7, 40e-6, 300)))
      control.ControlText.statusLine(robot, Some(settled)) should endWith("+35 ppm   -")
      web.WebJson.robot(robot, Some(settled), None).fields("clock").asJsObject.fields("driftSettled").toString shouldBe
        "true"
    }
  }
}
