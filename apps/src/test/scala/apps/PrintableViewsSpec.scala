package apps

import java.net.InetSocketAddress

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import spray.json._

import apps.web.WebJson
import naogateway.api.{LinkQuality, Printable, RobotSnapshot}

/** A robot whose role and agent carry terminal escape sequences (a stranger's forged keep-alive): the status lines and
  * the page show them with every control character replaced.
  */
class PrintableViewsSpec extends AnyWordSpec with Matchers {

  private val hostile = "keeper\u001b[2J\u001b]0;owned\u0007\u009b31m"
  private val robot = RobotSnapshot(1, new InetSocketAddress("127.0.0.1", 40000), role = Some(hostile),
    agent = Some(s"agent$hostile"), online = true, quality = LinkQuality.Good)

  "A robot's role with an escape sequence" should {
    "reach the status line with its control characters replaced" in {
      val line = StatusView.robotLine(robot, None)
      line.exists(Printable.control) shouldBe false
      line should include(s"role ${Printable.text(hostile)}")
      StatusView.render(StatusModel.empty.copy(robots = Vector(robot))).exists(_.exists(Printable.control)) shouldBe
        false
    }

    "reach the page with its control characters replaced" in {
      val card = WebJson.robot(robot, None, None)
      card.fields("role") shouldBe JsString(Printable.text(hostile))
      card.fields("agent").asInstanceOf[JsString].value.exists(Printable.control) shouldBe false
    }
  }

  "Printable text" should {
    "replace every C0, DEL and C1 character (ESC and the 8-bit CSI included) and keep the rest" in {
      val role = "keeper\u001b]0;owned\u0007\u001b[2J\u009b31m\r\nDEL\u007f tab\t"
      val shown = naogateway.api.Printable.text(role)
      shown.exists(naogateway.api.Printable.control) shouldBe false
      shown shouldBe "keeper\\u001b]0;owned\\u0007\\u001b[2J\\u009b31m\\u000d\\u000aDEL\\u007f tab\\u0009"
      naogateway.api.Printable.text("Läufer ⚽ 1") shouldBe "Läufer ⚽ 1"
    }
  }
}
