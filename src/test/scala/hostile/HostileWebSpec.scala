package hostile

import scala.concurrent.duration._
import scala.concurrent.{Await, Promise}
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.actor.typed.scaladsl.AskPattern._
import akka.http.scaladsl.Http
import akka.http.scaladsl.model.headers.RawHeader
import akka.http.scaladsl.model.ws.{Message, WebSocketRequest}
import akka.http.scaladsl.model.{ContentTypes, HttpEntity, StatusCode, StatusCodes}
import akka.http.scaladsl.server.Directives._
import akka.stream.scaladsl.{Flow, Keep, Sink, Source}
import akka.util.Timeout
import org.scalatest.concurrent.Eventually
import org.scalatest.wordspec.AnyWordSpecLike

import apps.control.{ControlServer, ControlSettings}
import apps.web.{Browser, WebDemo, WebSettings}
import naogateway.gateway.robot.VisionActor.{GridOption, RegionsOption}
import naogateway.proto.{RobotHealth, Status}
import naogateway.wire.{HeaderForm, MessageContents}
import naogateway.access.GatewayAccess
import naogateway.api.{GatewayAddresses, Printable, RobotSnapshot}

/** The web view against what a stranger can do from the operator's own browser: a page of another origin (another
  * loopback port) cannot open `/ws` (checked in headless Chromium), no WebSocket opens with a foreign `Origin`, and
  * with a token set a page without it switches no robot's camera on. And a stranger posing as a robot, whose role
  * carries terminal escape sequences: the page, robotctl and the status lines show it with them replaced.
  */
class HostileWebSpec extends ScalaTestWithActorTestKit(WebDemo.config) with AnyWordSpecLike with LogCapturing
    with Eventually {

  /** The view with the demo's settings (no token, loopback), as the launcher runs it beside simulated robots. */
  private lazy val open = new WebDemo(system, WebSettings(system))

  /** The same with a token. */
  private val Token = "t0ken-of-the-team"
  private lazy val guarded = new WebDemo(system, WebSettings(system).copy(token = Token))

  override def afterAll(): Unit = {
    Try(open.stop())
    Try(guarded.stop())
    super.afterAll()
  }

  /** The status of a WebSocket handshake to `uri` with `origin` (none: a program, not a browser). */
  private def handshake(uri: String, origin: Option[String], subprotocol: Option[String] = None): StatusCode = {
    val (upgrade, closer) = Http().singleWebSocketRequest(
      WebSocketRequest(uri, extraHeaders = origin.map(RawHeader("Origin", _)).toList, subprotocol = subprotocol),
      Flow.fromSinkAndSourceMat(Sink.ignore, Source.maybe[Message])(Keep.right)
    )
    try Await.result(upgrade, 10.seconds).response.status
    finally { closer.trySuccess(None); () }
  }

  /** The camera options robot `id` of `demo` has switched on now, as the robot itself holds them. */
  private def cameraOptions(demo: WebDemo, id: Int): Set[String] =
    Await.result(demo.fleet.state(id), 10.seconds).debugEnabled.intersect(Set(RegionsOption, GridOption))

  private def allOnline(demo: WebDemo): Unit =
    eventually(timeout(30.seconds), interval(200.millis)) {
      val robots = Await.result(demo.gateway.ask[Vector[RobotSnapshot]](GatewayAccess.GetRobots(_))(Timeout(10.seconds),
          system.scheduler), 10.seconds)
      robots.filter(_.online).map(_.robotId).toSet shouldBe Set(1, 2, 3)
    }

  /** What the stranger's page does: opens the view's /ws and writes what happened into window.wsEvents. */
  private def probeScript(port: Int): String =
    s"""window.wsEvents = [];
       |const ws = new WebSocket("ws://127.0.0.1:$port/ws");
       |ws.onopen = () => window.wsEvents.push("open");
       |ws.onmessage = () => window.wsEvents.push("message");
       |ws.onerror = () => window.wsEvents.push("error");
       |ws.onclose = (e) => window.wsEvents.push("close " + e.code);""".stripMargin

  "The web view without a token" should {
    "refuse a WebSocket whose Origin is another page's, on /ws, /foxglove and /control, and count it" in {
      val port = open.address.getPort
      val before = open.counters.originRefused
      handshake(open.ws(), Some("http://127.0.0.1:9")) shouldBe StatusCodes.Forbidden
      handshake(open.ws(), Some("https://evil.example")) shouldBe StatusCodes.Forbidden
      handshake(open.ws(), Some("null")) shouldBe StatusCodes.Forbidden
      handshake(s"ws://127.0.0.1:$port/foxglove", Some("http://evil.example"), Some("foxglove.websocket.v1")) shouldBe
        StatusCodes.Forbidden
      handshake(s"ws://127.0.0.1:$port/control", Some("http://evil.example")) shouldBe StatusCodes.Forbidden
      open.counters.originRefused shouldBe before + 5
      // The page's own origin and a program without one pass; neither counts as refused.
      handshake(open.ws(), Some(s"http://127.0.0.1:$port")) shouldBe StatusCodes.SwitchingProtocols
      handshake(open.ws(), None) shouldBe StatusCodes.SwitchingProtocols
      open.counters.originRefused shouldBe before + 5
    }

    "not let a page served from another loopback port open /ws in Chromium, while its own page can" in {
      Browser.missing.foreach(reason => cancel(reason))
      val viewPort = open.address.getPort
      val before = open.counters.originRefused
      // The stranger's page: any site the operator has open, here on another loopback port (another origin).
      val page = s"<!doctype html><html><body><p>elsewhere</p><script>${probeScript(viewPort)}</script></body></html>"
      val stranger = Await.result(Http().newServerAt("127.0.0.1", 0).bind(
          pathSingleSlash(get(complete(HttpEntity(ContentTypes.`text/html(UTF-8)`, page))))), 10.seconds)
      try {
        Browser.withChromium() { driver =>
          driver.get(s"http://127.0.0.1:${stranger.localAddress.getPort}/")
          def events = driver.executeScript("return (window.wsEvents || []).join(',')").asInstanceOf[String]
          eventually(timeout(15.seconds), interval(100.millis))(events should include("close"))
          events should not include "open"
          events should not include "message"
          open.counters.originRefused should be > before

          // The view's own page, the same script: it opens (the check is the origin, not the script).
          driver.get(open.page())
          driver.executeScript(probeScript(viewPort))
          eventually(timeout(15.seconds), interval(100.millis))(events should include("open"))
        }
      } finally stranger.terminate(2.seconds)
    }
  }

  "The web view with a token" should {
    "switch no camera on for a page without the token, nor for a foreign page with it, and on for its own page" in {
      Try(open.stop()) // one demo at a time: their simulated robots are told apart by address
      allOnline(guarded)
      val port = guarded.address.getPort
      handshake(guarded.ws(token = None), Some(s"http://127.0.0.1:$port")) shouldBe StatusCodes.Forbidden
      handshake(guarded.ws(token = Some("wrong")), None) shouldBe StatusCodes.Forbidden
      handshake(guarded.ws(), Some("http://127.0.0.1:9")) shouldBe StatusCodes.Forbidden
      guarded.counters.open shouldBe 0L
      // The view lists the robots every push (200 ms); none of the refused pages made it ask a camera.
      Thread.sleep(1500)
      (1 to 3).map(cameraOptions(guarded, _)) shouldBe Vector.fill(3)(Set.empty)

      // Its own page with the token: the cameras go on, which shows the check above could have failed.
      val closer = Promise[Option[Message]]()
      val (upgrade, _) = Http().singleWebSocketRequest(
        WebSocketRequest(guarded.ws(), extraHeaders = List(RawHeader("Origin", s"http://127.0.0.1:$port"))),
        Flow.fromSinkAndSourceMat(Sink.ignore,
          Source.maybe[Message].mapMaterializedValue(p => closer.future.foreach(p.success)(system.executionContext)))(
          Keep.left)
      )
      try {
        Await.result(upgrade, 10.seconds).response.status shouldBe StatusCodes.SwitchingProtocols
        eventually(timeout(15.seconds), interval(200.millis)) {
          (1 to 3).map(cameraOptions(guarded, _)) shouldBe Vector.fill(3)(Set(RegionsOption, GridOption))
        }
      } finally { closer.trySuccess(None); () }
    }

    "show a forged robot's role with escape sequences with its control characters replaced: page, robotctl, lines" in {
      allOnline(guarded)
      val role = "keeper\u001b[2J\u001b]0;owned\u0007\u009b31m"
      val forged = MessageContents.encodeFrame(
        MessageContents(
          42,
          status = Some(Status(timestamp = Some(1000L), teamID = Some(1), activeRole = Some(role))),
          robotHealth = Some(RobotHealth(batteryVoltage = Some(12.4f), posture = Some("stand"), uptimeMs = Some(1000),
              bootId = Some(1)))
        ),
        HeaderForm.Legacy
      ).toOption.get
      val robotPort = Await.result(guarded.gateway.ask[GatewayAddresses](GatewayAccess.GetAddresses(_))(
          Timeout(10.seconds), system.scheduler), 10.seconds).robots.getPort
      // The stranger, on a loopback address of its own, keeps sending the robot's keep-alive.
      val stranger = new java.net.DatagramSocket(new java.net.InetSocketAddress("127.0.0.250", 0))
      val target = new java.net.InetSocketAddress("127.0.0.1", robotPort)
      def forge(): Unit = stranger.send(new java.net.DatagramPacket(forged, forged.length, target))

      // The status lines, as the launcher prints them when piped.
      val lines = new java.util.concurrent.ConcurrentLinkedQueue[String]()
      val printer = spawn(apps.StatusPrinter(guarded.side.view, 200.millis,
          apps.StatusPrinter.LineOutput(l => { lines.add(l); () })))
      // robotctl, through a control port in front of the same middleware.
      val control = spawn(ControlServer(
          guarded.middleware,
          ControlSettings(system).copy(host = "127.0.0.1", port = 0),
          Some(ControlServer.GatewaySide(guarded.side.view, () => scala.concurrent.Future.successful(Vector.empty)))
        ))
      // The page's WebSocket, with the token from the page's own origin.
      val port = guarded.address.getPort
      val pushes = new java.util.concurrent.ConcurrentLinkedQueue[String]()
      val (upgrade, closer) = Http().singleWebSocketRequest(
        WebSocketRequest(guarded.ws(), extraHeaders = List(RawHeader("Origin", s"http://127.0.0.1:$port"))),
        Flow.fromSinkAndSourceMat(
          Sink.foreach[Message] {
            case t: akka.http.scaladsl.model.ws.TextMessage.Strict => pushes.add(t.text); ()
            case t: akka.http.scaladsl.model.ws.TextMessage        => t.textStream.runWith(Sink.ignore); ()
            case b: akka.http.scaladsl.model.ws.BinaryMessage      => b.dataStream.runWith(Sink.ignore); ()
          },
          Source.maybe[Message]
        )(Keep.right)
      )
      try {
        Await.result(upgrade, 10.seconds).response.status shouldBe StatusCodes.SwitchingProtocols
        val shown = Printable.text(role)
        import scala.jdk.CollectionConverters._
        eventually(timeout(20.seconds), interval(250.millis)) {
          forge()
          val robot42 = pushes.asScala.toVector.flatMap { text =>
            import spray.json._
            text.parseJson.asJsObject.fields.get("robots").toVector.flatMap(_.asInstanceOf[JsArray].elements)
              .map(_.asJsObject).filter(_.fields.get("id").contains(JsNumber(42)))
          }
          robot42 should not be empty
          robot42.last.fields("role") shouldBe spray.json.JsString(shown)
        }
        pushes.asScala.exists(_.exists(Printable.control)) shouldBe false

        eventually(timeout(20.seconds), interval(250.millis)) {
          forge()
          lines.asScala.exists(l => l.startsWith("robot 42") && l.contains(shown)) shouldBe true
        }
        lines.asScala.exists(_.exists(Printable.control)) shouldBe false

        val probe = createTestProbe[java.net.InetSocketAddress]()
        control ! ControlServer.GetAddress(probe.ref)
        val controlPort = probe.receiveMessage(10.seconds).getPort
        forge()
        val out = Vector.newBuilder[String]
        val err = Vector.newBuilder[String]
        naogateway.launcher.RobotCtl.run(Seq("--control", s"127.0.0.1:$controlPort", "status"), _ => None, out += _,
          err += _) shouldBe naogateway.launcher.RobotCtl.ExitOk
        val printed = out.result()
        printed.exists(l => l.startsWith("42") && l.contains(shown)) shouldBe true
        (printed ++ err.result()).exists(_.exists(Printable.control)) shouldBe false
      } finally {
        closer.trySuccess(None)
        stranger.close()
        testKit.stop(printer)
        testKit.stop(control)
      }
    }
  }
}
