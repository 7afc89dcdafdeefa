package apps.web

import scala.concurrent.duration._
import scala.concurrent.{Await, Promise}
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.actor.typed.scaladsl.AskPattern._
import akka.http.scaladsl.Http
import akka.http.scaladsl.model.StatusCodes
import akka.http.scaladsl.model.ws.{Message, WebSocketRequest}
import akka.stream.scaladsl.{Flow, Keep, Sink, Source}
import akka.util.Timeout
import org.scalatest.concurrent.Eventually
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.GatewayAccess
import naogateway.api.RobotSnapshot
import naogateway.gateway.robot.VisionActor.{GridOption, RegionsOption}

/** The web view asks the robots' cameras for HaViMo2 frames only while a page is connected: checked at the simulated
  * robots' own option state (what they send over the WiFi), with no page, one page, two, one, and none again.
  */
class WebCameraSpec extends ScalaTestWithActorTestKit(WebDemo.config) with AnyWordSpecLike with LogCapturing
    with Eventually {

  private lazy val demo = new WebDemo(system, WebSettings(system))

  override def afterAll(): Unit = {
    Try(demo.stop())
    super.afterAll()
  }

  /** A page's WebSocket that reads and drops what it gets until `close`. */
  private final class Page {
    private val closer = Promise[Option[Message]]()
    val (upgrade, done) = Http().singleWebSocketRequest(
      WebSocketRequest(demo.ws()),
      Flow.fromSinkAndSourceMat(Sink.ignore,
        Source.maybe[Message].mapMaterializedValue(p => closer.future.foreach(p.success)(system.executionContext)))(
        Keep.left)
    )
    def status: akka.http.scaladsl.model.StatusCode = Await.result(upgrade, 10.seconds).response.status
    def close(): Unit = closer.trySuccess(None)
  }

  /** The camera options robot `id` has switched on now, as the robot itself holds them. */
  private def cameraOptions(id: Int): Set[String] =
    Await.result(demo.fleet.state(id), 10.seconds).debugEnabled.intersect(Set(RegionsOption, GridOption))

  "The web view" should {
    "switch the robots' cameras on while a page is connected, and off when the last page leaves" in {
      eventually(timeout(30.seconds), interval(200.millis)) {
        val robots =
          Await.result(demo.gateway.ask[Vector[RobotSnapshot]](GatewayAccess.GetRobots(_))(Timeout(10.seconds),
              system.scheduler), 10.seconds)
        robots.filter(_.online).map(_.robotId).toSet shouldBe Set(1, 2, 3)
      }
      // The view has listed the robots for many pushes (200 ms apart), with nobody looking: no camera is asked.
      Thread.sleep(1500)
      (1 to 3).map(cameraOptions) shouldBe Vector.fill(3)(Set.empty)

      val first = new Page
      first.status shouldBe StatusCodes.SwitchingProtocols
      eventually(timeout(15.seconds), interval(200.millis)) {
        (1 to 3).map(cameraOptions) shouldBe Vector.fill(3)(Set(RegionsOption, GridOption))
      }
      val second = new Page
      second.status shouldBe StatusCodes.SwitchingProtocols
      first.close()
      // One page is still open: the cameras stay on.
      eventually(timeout(10.seconds))(demo.counters.open shouldBe 1L)
      Thread.sleep(1000)
      cameraOptions(1) shouldBe Set(RegionsOption, GridOption)

      second.close()
      eventually(timeout(15.seconds), interval(200.millis)) {
        (1 to 3).map(cameraOptions) shouldBe Vector.fill(3)(Set.empty)
      }
      // A page opened again switches them on again.
      val third = new Page
      try
        eventually(timeout(15.seconds), interval(200.millis))(cameraOptions(2) shouldBe Set(RegionsOption, GridOption))
      finally third.close()
      eventually(timeout(15.seconds), interval(200.millis))(cameraOptions(2) shouldBe Set.empty)
    }
  }
}
