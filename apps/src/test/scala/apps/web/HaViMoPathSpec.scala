package apps.web

import java.nio.file.{Files, Path}
import java.util.Base64

import scala.concurrent.duration._
import scala.concurrent.{Await, Promise}
import scala.jdk.CollectionConverters._
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.http.scaladsl.Http
import akka.http.scaladsl.model.ws.{Message, TextMessage, WebSocketRequest}
import akka.stream.scaladsl.{Flow, Keep, Sink, Source}
import com.typesafe.config.ConfigFactory
import org.scalatest.concurrent.Eventually
import org.scalatest.wordspec.AnyWordSpecLike
import spray.json._

import naogateway.gateway.recording.{McapReader, Recording}
import naogateway.sim.bus.{BioloidBus, BusWork}
import naogateway.sim.{Pose, Scene}
import naogateway.testkit.TempFiles
import naogateway.wire.{HaViMo, HaViMoRegion, MessageContents}

/** The HaViMo2 driver's frames reach the page and the recording unchanged: a simulated robot reads its camera over its
  * emulated Dynamixel bus (docs/protocol.md 6.9); the regions and the grid that bus's HaViMo2 holds for the robot's
  * view are the ones in the web view's overlay data (the WebSocket pushes the page draws from) and on the recording's
  * `/robot/<id>/message` channel, read back with the project's MCAP reader.
  */
class HaViMoPathSpec
    extends ScalaTestWithActorTestKit(HaViMoPathSpec.config)
    with AnyWordSpecLike
    with LogCapturing
    with Eventually {

  private lazy val demo = new WebDemo(system, WebSettings(system), robots = 1)
  @volatile private var stopped = false

  override def afterAll(): Unit = {
    if (!stopped) Try(demo.stop())
    try super.afterAll()
    finally TempFiles.deleteRecursively(HaViMoPathSpec.dir)
  }

  /** What robot 1's camera holds, read over a bus as the robot's firmware reads it: regions (6.5 records) and grid. */
  private def overTheBus(view: Vector[HaViMoRegion]): (Vector[HaViMoRegion], Vector[Byte]) = {
    val (_, frame) = BusWork.cameraCycle(BioloidBus(0L, view), withGrid = true)
    val read = frame.getOrElse(fail("the camera did not answer"))
    (HaViMo.decodeRegions(read.records).getOrElse(fail("the records do not decode")), read.grid.get.toVector)
  }

  "A simulated robot's HaViMo2 frames" should {
    "reach the web view's overlay and the recording as its emulated bus read them" in {
      val state = Await.result(demo.fleet.state(1), 30.seconds)
      // Robot 1 sits where it started, its head straight, the ball where the fleet put it: a still view.
      val view = Scene.regions(Scene(state.ball._1, state.ball._2), Pose(state.pose.x, state.pose.y, state.pose.theta),
        state.head._1, state.head._2)
      val (regions, grid) = overTheBus(view)
      regions should not be empty
      grid.exists(_ != 0) shouldBe true

      // A page: its pushes carry the frames (the regions every push, the grid when it changes).
      @volatile var pushes = Vector.empty[JsObject]
      val closer = Promise[Option[Message]]()
      val sink = Sink.foreach[Message] {
        case t: TextMessage.Strict => synchronized { pushes :+= t.text.parseJson.asJsObject }
        case other                 => other.asInstanceOf[TextMessage].textStream.runWith(Sink.ignore)
      }
      Http().singleWebSocketRequest(
        WebSocketRequest(demo.ws()),
        Flow.fromSinkAndSourceMat(sink,
          Source.maybe[Message].mapMaterializedValue(p =>
            closer.future.foreach(p.success)(system.executionContext)))(Keep.left)
      )
      def frames = pushes.flatMap(_.fields.get("vision")).flatMap(_.asJsObject.fields.get("1")).map(_.asJsObject)
      try
        eventually(timeout(60.seconds), interval(200.millis)) {
          frames.exists(_.fields.contains("grid")) shouldBe true
          frames.count(_.fields("regions") != JsArray.empty) should be >= 3
        }
      finally { closer.trySuccess(None); () }
      val shown = frames.filter(_.fields("regions") != JsArray.empty)
      all(shown.map(_.fields("regions"))) shouldBe JsArray(regions.map(WebJson.region))
      val grids = frames.flatMap(_.fields.get("grid")).map {
        case JsString(b64) => Base64.getDecoder.decode(b64).toVector
        case other         => fail(s"grid is $other")
      }
      grids should not be empty
      all(grids) shouldBe grid

      // The recording, once the gateway has closed it.
      demo.stop()
      stopped = true
      val files = eventually(timeout(30.seconds), interval(200.millis)) {
        val found = Files.list(HaViMoPathSpec.dir).iterator().asScala.filter(_.toString.endsWith(".mcap")).toVector
        found should not be empty
        found.map(f => McapReader.read(Files.readAllBytes(f)))
      }
      val messages = files.flatMap { contents =>
        contents.channels.values.find(_.topic == Recording.Topics.message(1)).toVector.flatMap { channel =>
          contents.messages.filter(_.channelId == channel.id).map(m => MessageContents.parse(m.data).toOption.get)
        }
      }
      val recordedRegions = messages.flatMap(_.havimoRegions).flatMap(_.records).map(b =>
        HaViMo.decodeRegions(b.toByteArray).getOrElse(fail("recorded records do not decode")))
      val recordedGrids = messages.flatMap(_.havimoGrid).map(_.cells.toByteArray.toVector)
      recordedRegions.filter(_.nonEmpty) should not be empty
      all(recordedRegions.filter(_.nonEmpty)) shouldBe regions
      recordedGrids should not be empty
      all(recordedGrids) shouldBe grid
    }
  }
}

/** The web view's test config with recording on, into a folder of the spec's own. */
object HaViMoPathSpec {
  val dir: Path = Files.createTempDirectory("havimo-path")

  val config: com.typesafe.config.Config = ConfigFactory.parseString(
    s"""naogateway.recording { enabled = on, directory = "${dir.toString}" }""").withFallback(WebDemo.config)
}
