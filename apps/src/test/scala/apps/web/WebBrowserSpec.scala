package apps.web

import java.nio.file.{Files, Paths, StandardCopyOption}

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.openqa.selenium.chrome.ChromeDriver
import org.openqa.selenium.{By, OutputType}
import org.scalatest.concurrent.Eventually
import org.scalatest.wordspec.AnyWordSpecLike

/** The demo's page in a real browser (headless Chromium): robots online, a game state that changes, the traffic plot
  * moving and robot 1's regions on its canvas, read from the canvases' pixels. Cancelled where no browser is installed.
  */
class WebBrowserSpec extends ScalaTestWithActorTestKit(WebDemo.config) with AnyWordSpecLike with LogCapturing
    with Eventually {

  private lazy val demo = new WebDemo(system, WebSettings(system))

  override def afterAll(): Unit = {
    Try(demo.stop())
    super.afterAll()
  }

  private def js[A](driver: ChromeDriver, script: String): A = driver.executeScript(script).asInstanceOf[A]

  /** Pixels of robot 1's camera canvas drawn at full opacity in a region colour (the grid's cells are translucent). */
  private val RegionPixels =
    """const c = document.querySelector('#robot-1 canvas.robot-vision');
      |if (!c) return -1;
      |const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      |const colours = [[0xff, 0x8c, 0x1a], [0xf5, 0xe0, 0x50], [0x3a, 0x78, 0xff]];
      |let n = 0;
      |for (let i = 0; i < d.length; i += 4)
      |  if (colours.some(k => d[i] === k[0] && d[i + 1] === k[1] && d[i + 2] === k[2])) n++;
      |return n;""".stripMargin

  "The demo's web view in Chromium" should {
    "show three robots online, a game state that changes, the traffic plot moving and robot 1's regions" in {
      Browser.missing.foreach(reason => cancel(reason))
      Browser.withChromium() { driver =>
        driver.get(demo.page())
        eventually(timeout(30.seconds), interval(250.millis)) {
          js[Long](driver, "return window.naogateway.robotsOnline") shouldBe 3L
          driver.findElements(By.cssSelector(".robot .robot-online.good")).asScala.size shouldBe 3
        }
        val states = scala.collection.mutable.LinkedHashSet.empty[String]
        eventually(timeout(30.seconds), interval(200.millis)) {
          Option(js[String](driver, "return window.naogateway.gameState")).foreach(states += _)
          states.size should be >= 2
        }
        driver.findElement(By.id("game-state")).getText should not be "-"

        val plot = "return document.querySelector('#traffic-plot canvas').toDataURL()"
        val before = js[String](driver, plot)
        val pointsBefore = js[Long](driver, "return window.naogateway.trafficPoints")
        eventually(timeout(10.seconds), interval(250.millis)) {
          js[Long](driver, "return window.naogateway.trafficPoints") should be > pointsBefore
          js[String](driver, plot) should not be before
        }

        eventually(timeout(20.seconds), interval(250.millis)) {
          js[Long](driver, RegionPixels) should be >= 8L
        }
        driver.findElements(By.cssSelector("#events li.event-online")).asScala.size should be >= 3
        // Each simulated robot's 18 servos (its keep-alive's telemetry, once a second) in its card's servo table.
        eventually(timeout(20.seconds), interval(250.millis)) {
          js[Long](driver, "return window.naogateway.servoRows[1] || 0") shouldBe 18L
          val rows = driver.findElements(By.cssSelector("#robot-1 table.robot-servos tbody tr")).asScala
          rows.size shouldBe 18
          rows.head.findElements(By.tagName("td")).asScala.map(_.getText).last should endWith("°C")
        }
        /* Each card's clock line, drawn by the page from the push: a drift (settled) or `drift settling`, and the
         * offset. */
        eventually(timeout(20.seconds), interval(250.millis)) {
          val clocks = driver.findElements(By.cssSelector(".robot .robot-clock")).asScala.map(_.getText)
          clocks.size shouldBe 3
          all(clocks) should fullyMatch regex """(-?\d+ ± \d+ ppm|drift settling), offset ± [\d.]+ ms \(\d+ samples\)"""
        }

        val shot = Paths.get("target", "web", "web-view.png")
        Files.createDirectories(shot.getParent)
        Files.copy(driver.getScreenshotAs(OutputType.FILE).toPath, shot, StandardCopyOption.REPLACE_EXISTING)
        Files.size(shot) should be > 10000L
      }
    }
  }
}
