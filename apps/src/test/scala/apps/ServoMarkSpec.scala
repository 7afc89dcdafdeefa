package apps

import java.net.InetSocketAddress

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.api.{LinkQuality, RobotSnapshot, ServoReading, ServoReadings}
import robotmiddleware.ServoLimits

/** The terminal views mark a robot's hot and low-voltage servos (`robotmiddleware.servos`): the launcher's status
  * screen and line view (StatusView) and `robotctl status` (ControlServer.statusLine).
  */
class ServoMarkSpec extends AnyWordSpec with Matchers {

  private def servos(readings: ServoReading*) = Some(ServoReadings(readings.toVector, Some(0L), 0L))
  private val calm = servos(ServoReading(1, Some(512), Some(0), Some(12.0), Some(40)),
    ServoReading(2, Some(512), Some(0), Some(12.0), Some(41)), ServoReading(3, silent = true))
  private val troubled = servos(
    ServoReading(1, Some(512), Some(0), Some(12.0), Some(70)),
    ServoReading(2, Some(512), Some(0), Some(9.5), Some(41)),
    ServoReading(3, silent = true),
    ServoReading(7, Some(512), Some(0), Some(9.9), Some(66))
  )
  private val robot = RobotSnapshot(2, new InetSocketAddress("127.0.0.1", 3838), online = true,
    quality = LinkQuality.Good, servos = calm)

  "A robot's servo mark" should {
    "name the hot and the low-voltage servos by the limits, and nothing while none is (or none was read)" in {
      RobotRow.servoMark(robot, ServoLimits()) shouldBe None
      RobotRow.servoMark(robot.copy(servos = None), ServoLimits()) shouldBe None
      RobotRow.servoMark(robot.copy(servos = troubled), ServoLimits()) shouldBe
        Some("SERVOS hot 1,7 low-voltage 2,7")
      RobotRow.servoMark(robot.copy(servos = troubled), ServoLimits(hotCelsius = 68, lowVolts = 9.6)) shouldBe
        Some("SERVOS hot 1 low-voltage 2")
    }

    "end the status screen's robot line and robotctl status's line" in {
      val hot = robot.copy(servos = troubled)
      StatusView.robotLine(robot, None) should not include "SERVOS"
      StatusView.robotLine(hot, None) should endWith(" SERVOS hot 1,7 low-voltage 2,7")
      StatusView.render(StatusModel(Vector(hot), Map.empty, None, None)).exists(_.endsWith("low-voltage 2,7")) shouldBe
        true
      control.ControlText.statusLine(robot, None) should not include "SERVOS"
      control.ControlText.statusLine(hot, None) should endWith(" SERVOS hot 1,7 low-voltage 2,7")
      control.ControlText.statusLine(hot, None, limits = ServoLimits(hotCelsius = 80, lowVolts = 5.0)) should
        not include "SERVOS"
    }

    "be news in the line view when it appears or changes, not while it stays" in {
      val before = StatusModel(Vector(robot), Map.empty, None, None)
      val hot = before.copy(robots = Vector(robot.copy(servos = troubled)))
      StatusView.changes(before, hot) shouldBe Vector(StatusView.robotLine(robot.copy(servos = troubled), None))
      StatusView.changes(hot, hot) shouldBe empty
      StatusView.changes(hot, before) should have size 1
    }
  }
}
