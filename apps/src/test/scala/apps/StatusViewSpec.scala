package apps

import java.net.InetSocketAddress

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.{LinkQuality, LinkStats, RobotSnapshot}

class StatusViewSpec extends AnyWordSpec with Matchers {
  private val address = new InetSocketAddress("127.0.0.1", 40000)
  private val sitting = RobotSnapshot(1, address, role = Some("keeper"), posture = Some("sit"), batteryVoltage = Some(12.4),
    online = true, quality = LinkQuality.Good)
  private val link = LinkStats(1, 10, 10, 300, 300, Some(0.4), 0.0, 0, Map.empty)

  "The status view" should {
    "show each robot's id, online state, battery, posture, role, round-trip time and address" in {
      val line = StatusView.robotLine(sitting, Some(link))
      Seq("robot 1", "online", "12.40 V", "sit", "keeper", "0.4 ms", "127.0.0.1:40000").foreach(line should include(_))
    }
    "print one plain line per robot and change of online state or posture, and nothing when nothing changed" in {
      val none = StatusModel(Vector.empty, Map.empty, None, None)
      val first = StatusModel(Vector(sitting), Map(1 -> link), None, None)
      StatusView.changes(none, first).map(_.take(20)) shouldBe Vector("robot 1   online  go")
      StatusView.changes(first, first) shouldBe empty
      val standing = first.copy(robots = Vector(sitting.copy(posture = Some("stand"))))
      StatusView.changes(first, standing).head should include("stand")
      val offline = first.copy(robots = Vector(sitting.copy(online = false)))
      StatusView.changes(first, offline).head should include("offline")
    }
    "render a screen with the team's traffic and the game" in {
      val screen = StatusView.render(StatusModel(Vector(sitting), Map.empty, None, None))
      screen.head shouldBe "naogateway - 1 robot(s), 1 online"
      screen.exists(_.contains("no GameController")) shouldBe true
    }
  }
}
