package apps.web

import java.net.InetSocketAddress

import scala.concurrent.Await
import scala.concurrent.duration._
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.http.scaladsl.Http
import akka.http.scaladsl.model.ws.WebSocketRequest
import akka.http.scaladsl.model.{HttpRequest, StatusCodes}
import akka.stream.scaladsl.{Flow, Sink, Source}
import org.openqa.selenium.interactions.Actions
import org.openqa.selenium.support.ui.Select
import org.openqa.selenium.{By, Keys}
import org.scalatest.concurrent.Eventually
import org.scalatest.wordspec.AnyWordSpecLike
import spray.json._

/** The control panel: in Chromium, a key press and a simulated gamepad walk robot 2 of the demo through the middleware;
  * refused in competition mode, without a token, and when off.
  */
class WebControlSpec extends ScalaTestWithActorTestKit(WebDemo.config) with AnyWordSpecLike with LogCapturing
    with Eventually {

  private val Token = "panel-token"
  private val settings = {
    val s = WebSettings(system)
    s.copy(token = Token, control = s.control.copy(enabled = true))
  }
  private lazy val demo = new WebDemo(system, settings)

  override def afterAll(): Unit = {
    Try(demo.stop())
    super.afterAll()
  }

  private def posture(driver: org.openqa.selenium.WebDriver, robot: Int): String =
    Try(driver.findElement(By.cssSelector(s"#robot-$robot .robot-posture")).getText).getOrElse("")

  "The control panel" should {
    "walk robot 2 with a key and with a gamepad, and stop it when they are let go" in {
      Browser.missing.foreach(reason => cancel(reason))
      Browser.withChromium() { driver =>
        driver.get(demo.page(Some(Token)))
        eventually(timeout(30.seconds), interval(250.millis)) {
          driver.findElement(By.id("control")).isDisplayed shouldBe true
          driver.findElements(By.cssSelector("#control-robot option[value='2']")).size shouldBe 1
          posture(driver, 2) should not be ""
        }
        new Select(driver.findElement(By.id("control-robot"))).selectByValue("2")
        driver.findElement(By.tagName("h1")).click() // the keys go to the page, not the select

        new Actions(driver).keyDown("w").perform()
        eventually(timeout(20.seconds), interval(200.millis))(posture(driver, 2) shouldBe "walking")
        new Actions(driver).keyUp("w").perform()
        eventually(timeout(10.seconds), interval(200.millis))(posture(driver, 2) should not be "walking")
        posture(driver, 1) should not be "walking"

        // A gamepad with its left stick pushed forward, as the Gamepad API reports one.
        driver.executeScript("navigator.getGamepads = () => [{ connected: true, axes: [0, -1, 0, 0], buttons: [] }]")
        eventually(timeout(20.seconds), interval(200.millis))(posture(driver, 2) shouldBe "walking")
        driver.executeScript("navigator.getGamepads = () => []")
        eventually(timeout(10.seconds), interval(200.millis))(posture(driver, 2) should not be "walking")
        new Actions(driver).sendKeys(Keys.SPACE).perform()
        val results = driver.executeScript("return window.naogatewayControl.results.map(r => r.ok)").toString
        results should include("true")
      }
    }

    "be refused in competition mode, without a token, and when off" in {
      WebServer.availability(settings, competition = true).enabled shouldBe false
      WebServer.availability(settings, competition = true).reason should include("competition")
      WebServer.availability(settings.copy(token = ""), competition = false).reason should include("token")
      WebServer.availability(settings.copy(control = settings.control.copy(enabled = false)), competition = false)
        .enabled shouldBe false
      WebServer.availability(settings, competition = false).enabled shouldBe true

      val competing = spawn(WebServer(demo.side.copy(competition = true), demo.middleware, settings))
      val probe = createTestProbe[Option[InetSocketAddress]]()
      competing ! WebServer.GetAddress(probe.ref)
      val port = probe.receiveMessage(10.seconds).get.getPort
      val state =
        Await.result(Http().singleRequest(HttpRequest(uri = s"http://127.0.0.1:$port/control/state")), 10.seconds)
      Await.result(state.entity.toStrict(5.seconds), 5.seconds).data.utf8String.parseJson.asJsObject.fields(
        "enabled") shouldBe JsFalse
      val (upgrade, _) = Http().singleWebSocketRequest(WebSocketRequest(s"ws://127.0.0.1:$port/control?token=$Token"),
        Flow.fromSinkAndSource(Sink.ignore, Source.maybe))
      Await.result(upgrade, 10.seconds).response.status shouldBe StatusCodes.Forbidden
      testKit.stop(competing)

      // On the demo's server, the panel is on but only with the token.
      val (wrong, _) =
        Http().singleWebSocketRequest(WebSocketRequest(s"ws://127.0.0.1:${demo.address.getPort}/control?token=nope"),
          Flow.fromSinkAndSource(Sink.ignore, Source.maybe))
      Await.result(wrong, 10.seconds).response.status shouldBe StatusCodes.Forbidden
    }

    "read a page's requests totally, clamping speeds to teleop's" in {
      WebControl.drive("""{"op":"walk","robot":2,"vx":5,"vy":-5,"omega":0.1}""") shouldBe WebControl.Walk(2, 0.2, -0.1,
        0.1)
      WebControl.drive("""{"op":"stop","robot":3}""") shouldBe WebControl.Stop(3)
      WebControl.drive("""{"op":"walk","robot":2}""") shouldBe a[WebControl.Bad]
      WebControl.drive("""{"op":"walk","robot":-1,"vx":0,"vy":0,"omega":0}""") shouldBe a[WebControl.Bad]
      WebControl.drive("""{"op":"reset","robot":2}""") shouldBe a[WebControl.Bad]
      WebControl.drive("\u0000") shouldBe a[WebControl.Bad]
    }
  }
}
