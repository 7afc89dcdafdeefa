package apps.web

import java.net.InetSocketAddress

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import spray.json._

import naogateway.wire.HaViMoRegion
import naogateway.api.{
  GatewayStats,
  LinkQuality,
  LinkStats,
  RobotOffline,
  RobotOnline,
  RobotSnapshot,
  ServoReading,
  ServoReadings,
  TrafficStats
}
import robotmiddleware.ServoLimits

/** The web view's model without actors: what it keeps, what it logs, and the JSON it renders. */
class WebModelSpec extends AnyWordSpec with Matchers {

  private val address = new InetSocketAddress("127.0.0.1", 3838)
  private def robot(id: Int, battery: Option[Double] = Some(12.0)) =
    RobotSnapshot(id, address, role = Some("striker"), batteryVoltage = battery, online = true,
      quality = LinkQuality.Good)
  private def link(id: Int, rejected: Map[String, Long] = Map.empty, rtt: Option[Double] = Some(1.5)) =
    LinkStats(id, 10, 10, 100, 100, rtt, 0.25, 0, rejected)
  private def traffic(competition: Boolean, running: Boolean) =
    TrafficStats(1000, 2000, 10000, Map.empty, 1, 1, 0, 0, running, competition)
  private val blank = WebModel(historyPoints = 5, maxEvents = 3)

  "The web view's model" should {
    "keep at most history-points points per plot and max events log lines, newest first" in {
      val m = (1 to 20).foldLeft(blank.withRobots(Vector(robot(1))).withTraffic(traffic(false, false), 0, 0))((m, i) =>
        m.sampled(i.toDouble))
      m.robotHistory(1).map(_.t) shouldBe Vector(16.0, 17.0, 18.0, 19.0, 20.0)
      m.trafficHistory.map(_.t) shouldBe Vector(16.0, 17.0, 18.0, 19.0, 20.0)
      m.sampleCount shouldBe 20
      val logged = (1 to 10).foldLeft(m)((m, i) => m.withEvent(RobotOffline(i, "test"), i.toDouble, i.toLong))
      logged.events.map(_.robotId) shouldBe Vector(Some(10), Some(9), Some(8))
      logged.eventCount shouldBe 10
    }

    "log refusals by kind as their counters grow, and changes of the gate and the game state" in {
      val m0 = blank.withRobots(Vector(robot(1))).withLinks(Vector(link(1, Map("bad-signature" -> 2))), 0, 0)
      m0.events shouldBe empty // the first figures are not news
      val m1 = m0.withLinks(Vector(link(1, Map("bad-signature" -> 5, "too-short" -> 1))), 1, 1)
      m1.events.map(_.text) shouldBe Vector("robot 1: 1 refused (too-short, 1 in all)",
        "robot 1: 3 refused (bad-signature, 5 in all)")
      val m2 = m1.withTraffic(traffic(competition = true, running = false), 2, 2).withTraffic(
        traffic(competition = true, running = true), 3, 3)
      m2.events.head.kind shouldBe "gate"
      m2.events.head.text should include("CLOSED")
      val stats = GatewayStats(0, 0, 0, Map("unknown-robot" -> 1), 1)
      val m3 = m2.withGatewayStats(stats, 4, 4).withGatewayStats(stats.copy(rejected = Map("unknown-robot" -> 4)), 5, 5)
      m3.events.head.text shouldBe "gateway: 3 refused (unknown-robot, 4 in all)"
    }

    "put the GameController's penalty and the development flag on a robot's card" in {
      // v20-playing.bin: player 3 of team 12 pushed, 25 s left (the status screen's rule: player number = robot id).
      val game = naogateway.wire.gamecontroller.GameControllerCodec.decodeControl(
        apps.StatusViewSpec.vector("v20-playing.bin")).toOption
      val three = robot(3).copy(teamId = Some(12))
      val card = WebJson.robot(three, None, Some("signed"), game)
      card.fields("penalty") shouldBe JsObject("name" -> JsString("pushing"), "secondsLeft" -> JsNumber(25))
      card.fields("development") shouldBe JsBoolean(false)
      WebJson.robot(three.copy(teamId = Some(7)), None, None, game).fields("penalty") shouldBe JsNull
      WebJson.robot(three, None, None, None).fields("penalty") shouldBe JsNull
    }

    "put the servo table on a robot's card, hot, low-voltage and silent servos marked" in {
      val servos = ServoReadings(
        Vector(
          ServoReading(1, Some(512), Some(-40), Some(12.1), Some(41)),
          ServoReading(2, Some(0), Some(300), Some(9.8), Some(65), error = 32),
          ServoReading(3, silent = true)),
        Some(4L),
        0L
      )
      val card = WebJson.robot(robot(1).copy(servos = Some(servos)), None, None, None, ServoLimits(65, 10.0))
      val table = card.fields("servos").asJsObject
      table.fields("busErrors") shouldBe JsNumber(4)
      val rows = table.fields("list").asInstanceOf[JsArray].elements.map(_.asJsObject.fields)
      rows.map(_("id")) shouldBe Vector(JsNumber(1), JsNumber(2), JsNumber(3))
      rows(0)("position") shouldBe JsNumber(512)
      rows(0)("degrees") shouldBe JsNumber(0.0)
      rows(0)("load") shouldBe JsNumber(-40)
      rows(0)("voltage") shouldBe JsNumber(12.1)
      rows(0)("temperature") shouldBe JsNumber(41)
      rows.map(r => (r("hot"), r("lowVoltage"), r("silent"))) shouldBe Vector(
        (JsFalse, JsFalse, JsFalse), (JsTrue, JsTrue, JsFalse), (JsFalse, JsFalse, JsTrue))
      rows(1)("error") shouldBe JsNumber(32)
      rows(2)("position") shouldBe JsNull
      // Other limits, other marks; no telemetry, no table.
      val lenient = WebJson.robot(robot(1).copy(servos = Some(servos)), None, None, None, ServoLimits(70, 9.0))
      lenient.fields("servos").asJsObject.fields("list").asInstanceOf[JsArray].elements(1).asJsObject.fields(
        "hot") shouldBe
        JsFalse
      WebJson.robot(robot(1), None, None).fields("servos") shouldBe JsNull
      // The push renders with the model's limits.
      val pushed =
        blank.copy(servoLimits = ServoLimits(40, 10.0)).withRobots(Vector(robot(1).copy(servos = Some(servos))))
      val first = WebJson.push(pushed, 0, 0, 0, Set.empty, hello = true).parseJson.asJsObject.fields("robots")
        .asInstanceOf[JsArray].elements.head.asJsObject.fields("servos").asJsObject.fields("list")
        .asInstanceOf[JsArray].elements.head.asJsObject.fields("hot")
      first shouldBe JsTrue
    }

    "keep frames only of robots it lists, and drop a robot's plots and frame with it" in {
      val region = HaViMoRegion(1, 1, 20, 200, 300, 20, 5, 30, 10)
      val m = blank.withRobots(Vector(robot(1))).withRegions(1, 7, Vector(region)).withRegions(99, 1, Vector(region))
        .withGrid(1, 8, Array.fill[Byte](768)(0x21)).sampled(1)
      m.vision.keySet shouldBe Set(1)
      m.vision(1).regions shouldBe Vector(region)
      m.vision(1).gridFrame shouldBe 8
      val gone = m.withRobots(Vector(robot(2)))
      gone.vision shouldBe empty
      gone.robotHistory.keySet shouldBe empty
    }

    "render JSON whatever the figures hold: NaN and missing values as null" in {
      val m = blank.withRobots(Vector(robot(1, battery = Some(Double.NaN)), RobotSnapshot(2, null, quality = null)))
        .withLinks(Vector(link(1, rtt = Some(Double.PositiveInfinity))), 0, 0).sampled(1)
        .withEvent(RobotOnline(1, address), 1, 1)
      val json = WebJson.push(m, 1.0, 1, 1, Set.empty, hello = true).parseJson.asJsObject
      json.fields("type") shouldBe JsString("hello")
      val robots = json.fields("robots").asInstanceOf[JsArray].elements.map(_.asJsObject)
      robots.map(_.fields("id")) shouldBe Vector(JsNumber(1), JsNumber(2))
      robots.head.fields("battery") shouldBe JsNull
      robots.head.fields("rttMs") shouldBe JsNull
      robots(1).fields("address") shouldBe JsNull
      robots(1).fields("quality") shouldBe JsNull
      json.fields("game").asJsObject.fields("state") shouldBe JsNull
      json.fields("events").asInstanceOf[JsArray].elements.map(_.asJsObject.fields("kind")) shouldBe Vector(
        JsString("online"))
      val samples =
        json.fields("samples").asJsObject.fields("robots").asJsObject.fields("1").asInstanceOf[JsArray].elements
      samples shouldBe Vector(JsArray(JsNumber(1), JsNull, JsNull, JsNumber(0.25)))
    }

    "send a robot's grid only when asked, regions always" in {
      val m = blank.withRobots(Vector(robot(1))).withRegions(1, 1, Vector(HaViMoRegion(1, 1, 1, 1, 1, 1, 1, 1, 1)))
        .withGrid(1, 1, Array.fill[Byte](768)(3))
      val without = WebJson.push(m, 0, 0, 0, Set.empty, hello = false).parseJson.asJsObject
      val withGrid = WebJson.push(m, 0, 0, 0, Set(1), hello = false).parseJson.asJsObject
      def vision(j: JsObject) = j.fields("vision").asJsObject.fields("1").asJsObject
      vision(without).fields.keySet shouldBe Set("frame", "regions")
      java.util.Base64.getDecoder.decode(vision(withGrid).fields("grid").asInstanceOf[JsString].value)
        .toVector shouldBe Vector.fill[Byte](768)(3)
    }
  }
}
