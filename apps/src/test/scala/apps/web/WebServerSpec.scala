package apps.web

import java.io.{ByteArrayOutputStream, InputStream}
import java.net.{InetSocketAddress, Socket}
import java.nio.charset.StandardCharsets

import scala.concurrent.duration._
import scala.concurrent.{Await, Promise}
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.http.scaladsl.Http
import akka.http.scaladsl.model.ws.{Message, TextMessage, WebSocketRequest}
import akka.http.scaladsl.model.{HttpRequest, StatusCodes}
import akka.stream.scaladsl.{Flow, Keep, Sink, Source}
import akka.util.ByteString
import com.typesafe.config.ConfigFactory
import org.scalatest.concurrent.Eventually
import org.scalatest.wordspec.AnyWordSpecLike
import spray.json._

/** The web view's server as clients see it: the page from the jar, the pushes of the demo, and what bad clients get. */
class WebServerSpec
    extends ScalaTestWithActorTestKit(
      // Small socket buffers, so a client that never reads holds the server back after kilobytes, not megabytes.
      ConfigFactory.parseString("akka.http.server.socket-options.so-send-buffer-size = 8k").withFallback(
        WebDemo.config))
    with AnyWordSpecLike
    with LogCapturing
    with Eventually {

  private val settings = WebSettings(system)
  private lazy val demo = new WebDemo(system, settings)

  override def afterAll(): Unit = {
    Try(demo.stop())
    super.afterAll()
  }

  private def get(uri: String) = {
    val response = Await.result(Http().singleRequest(HttpRequest(uri = uri)), 10.seconds)
    val body = Await.result(response.entity.toStrict(10.seconds), 10.seconds).data
    (response.status, response.entity.contentType.toString, body)
  }

  /** A WebSocket client that keeps every text message it gets (parsed) until `close` completes. */
  private final class Client(uri: String) {
    @volatile var messages = Vector.empty[JsObject]
    private val closer = Promise[Option[Message]]()
    private val sink = Sink.foreach[Message] {
      case t: TextMessage.Strict => synchronized { messages :+= t.text.parseJson.asJsObject }
      case other                 => other.asInstanceOf[TextMessage].textStream.runWith(Sink.ignore)
    }
    val (upgrade, done) = Http().singleWebSocketRequest(
      WebSocketRequest(uri),
      Flow.fromSinkAndSourceMat(sink,
        Source.maybe[Message].mapMaterializedValue(p =>
          closer.future.foreach(p.success)(system.executionContext)))(Keep.left)
    )
    def status: akka.http.scaladsl.model.StatusCode = Await.result(upgrade, 10.seconds).response.status
    def close(): Unit = closer.trySuccess(None)
    def pushes: Vector[JsObject] = messages
  }

  private def robotsOnline(m: JsObject): Int =
    m.fields("robots").asInstanceOf[JsArray].elements.count(_.asJsObject.fields("online") == JsTrue)

  private def field(m: JsObject, path: String*): JsValue =
    /* A page's first pushes have no frames yet (the cameras are asked once a page is connected): a missing part is
     * JsNull. */
    path.foldLeft[JsValue](m) {
      case (o: JsObject, k) => o.fields.getOrElse(k, JsNull)
      case _                => JsNull
    }

  "The web view" should {
    "serve the page and every asset it loads from the jar, and nothing else" in {
      val (status, contentType, body) = get(demo.page())
      status shouldBe StatusCodes.OK
      contentType should startWith("text/html")
      val html = body.utf8String
      val assets = "(?:src|href)=\"(assets/[^\"]+)\"".r.findAllMatchIn(html).map(_.group(1)).toVector
      assets should contain allOf ("assets/app.js",
        "assets/app.css", "assets/uPlot.iife.min.js", "assets/uPlot.min.css")
      // No address outside the gateway: the page must work at a field without internet.
      html should not include "http"
      assets.foreach { a =>
        val (s, _, b) = get(demo.page() + a)
        withClue(a)(s shouldBe StatusCodes.OK)
        b.length should be > 100
      }
      get(demo.page() + "assets/uPlot.iife.min.js")._3.utf8String should include("uPlot")
      get(demo.page() + "assets/../reference.conf")._1 shouldBe StatusCodes.NotFound
      get(demo.page() + "assets/nothing.js")._1 shouldBe StatusCodes.NotFound
    }

    "push the demo: three robots online, a changing game state, traffic samples, robot 1's regions, the event log" in {
      val client = new Client(demo.ws())
      try {
        eventually(timeout(30.seconds), interval(200.millis)) {
          val all = client.pushes
          all.head.fields("type") shouldBe JsString("hello")
          all.map(robotsOnline).max shouldBe 3
          all.map(field(_, "game", "state")).filter(_ != JsNull).distinct.size should be >= 2
          all.flatMap(m => field(m, "samples", "traffic").asInstanceOf[JsArray].elements).size should be >= 3
          all.exists(m =>
            field(m, "vision", "1", "regions") match {
              case JsArray(regions) => regions.nonEmpty
              case _                => false
            }) shouldBe true
          all.exists(m => field(m, "vision", "1", "grid").isInstanceOf[JsString]) shouldBe true
          all.flatMap(m =>
            m.fields("events").asInstanceOf[JsArray].elements.map(e => field(e.asJsObject, "kind"))) should contain(
            JsString("online"))
        }
        val robot = client.pushes.last.fields("robots").asInstanceOf[JsArray].elements.head.asJsObject
        robot.fields.keySet should contain allOf ("battery",
          "posture", "role", "rttMs", "loss", "clock", "signing", "refused")
        robot.fields("signing") shouldBe JsString("off")
        // Pushes come at the configured interval, not faster; a push that carries a new event (the simulated
        // GameController changes state on its own) may come sooner, as WebView documents, and is not counted.
        val before = client.pushes.size
        Thread.sleep(2000)
        val window = client.pushes.drop(before)
        val withEvents = window.count(_.fields("events").asInstanceOf[JsArray].elements.nonEmpty)
        window.size should be >= 5
        (window.size - withEvents) should be <= 2000 / 200 + 2
      } finally client.close()
    }

    "refuse a WebSocket without the token when one is set, and serve one with it" in {
      val guarded = spawn(WebServer(demo.side, demo.middleware, settings.copy(token = "s3cret-token")))
      val probe = createTestProbe[Option[InetSocketAddress]]()
      guarded ! WebServer.GetAddress(probe.ref)
      val port = probe.receiveMessage(10.seconds).get.getPort
      new Client(s"ws://127.0.0.1:$port/ws").status shouldBe StatusCodes.Forbidden
      new Client(s"ws://127.0.0.1:$port/ws?token=wrong").status shouldBe StatusCodes.Forbidden
      val ok = new Client(s"ws://127.0.0.1:$port/ws?token=s3cret-token")
      ok.status shouldBe StatusCodes.SwitchingProtocols
      eventually(timeout(10.seconds))(ok.pushes should not be empty)
      ok.close()
      testKit.stop(guarded)
    }

    "refuse to serve beyond loopback without a token" in {
      settings.copy(bindAddress = "0.0.0.0").refusal shouldBe defined
      settings.copy(bindAddress = "0.0.0.0", token = "t").refusal shouldBe None
      settings.refusal shouldBe None
    }

    "serve 50 pages at once, and refuse the ones beyond max-clients" in {
      // A server of its own whose clients may lag 20 s behind: this is about many clients, not slow ones (the 50
      // clients share this JVM, and a loaded machine makes some of them slow readers).
      val many = spawn(WebServer(demo.side, demo.middleware, settings.copy(clientBuffer = 100)))
      val manyAt = createTestProbe[Option[InetSocketAddress]]()
      many ! WebServer.GetAddress(manyAt.ref)
      val manyPort = manyAt.receiveMessage(10.seconds).get.getPort
      val clients = Vector.fill(50)(new Client(s"ws://127.0.0.1:$manyPort/ws"))
      try {
        eventually(timeout(30.seconds), interval(200.millis)) {
          all(clients.map(_.pushes.size)) should be >= 2
        }
        val counters = createTestProbe[WebServer.Counters]()
        many ! WebServer.GetCounters(counters.ref)
        counters.receiveMessage(10.seconds) shouldBe WebServer.Counters(50, 0, 0, 0)
        val small = spawn(WebServer(demo.side, demo.middleware, settings.copy(maxClients = 2)))
        val probe = createTestProbe[Option[InetSocketAddress]]()
        small ! WebServer.GetAddress(probe.ref)
        val port = probe.receiveMessage(10.seconds).get.getPort
        val two = Vector.fill(2)(new Client(s"ws://127.0.0.1:$port/ws"))
        two.foreach(_.status shouldBe StatusCodes.SwitchingProtocols)
        new Client(s"ws://127.0.0.1:$port/ws").status shouldBe StatusCodes.ServiceUnavailable
        two.foreach(_.close())
        testKit.stop(small)
      } finally clients.foreach(_.close())
      eventually(timeout(10.seconds)) {
        val counters = createTestProbe[WebServer.Counters]()
        many ! WebServer.GetCounters(counters.ref)
        counters.receiveMessage(10.seconds).open shouldBe 0L
      }
      testKit.stop(many)
    }

    "ignore what pages send, close on a malformed frame, and keep serving" in {
      val before = demo.counters
      val chatty = new Client(demo.ws())
      eventually(timeout(10.seconds))(chatty.pushes should not be empty)
      // Junk text and binary messages from a page are read, counted and dropped.
      Http().singleWebSocketRequest(
        WebSocketRequest(demo.ws()),
        Flow.fromSinkAndSource(
          Sink.ignore,
          Source(Vector[Message](
              TextMessage("{\"op\":\"subscribe\",\"channel\":\"nowhere\"}"),
              TextMessage("\u0000\uffff not json"),
              akka.http.scaladsl.model.ws.BinaryMessage(ByteString(Array.fill[Byte](1000)(-1)))
            )).concat(Source.maybe)
        )
      )
      eventually(timeout(10.seconds))(demo.counters.ignoredFrames should be >= before.ignoredFrames + 3)

      // A raw connection that upgrades, then sends bytes that are no WebSocket frame (unmasked, reserved opcode).
      val socket = upgraded()
      socket.getOutputStream.write(Array[Byte](0x83.toByte, 0x7f, -1, -1, -1, -1, -1, -1, -1, -1, 1, 2, 3))
      socket.getOutputStream.flush()
      socket.setSoTimeout(10000)
      val in = socket.getInputStream
      // The server answers with a close frame (or just closes) and the connection ends.
      drain(in, 1 << 20) should be < (1 << 20)
      socket.close()
      chatty.pushes.size should be > 0
      val after = chatty.pushes.size
      eventually(timeout(5.seconds))(chatty.pushes.size should be > after)
      chatty.close()
    }

    "disconnect a client that never reads, and keep serving the others" in {
      val before = demo.counters.slowDropped
      val reader = new Client(demo.ws())
      val socket = new Socket()
      socket.setReceiveBufferSize(4096)
      socket.connect(new InetSocketAddress("127.0.0.1", demo.address.getPort), 5000)
      handshake(socket)
      // Never read: the pushes pile up in the socket buffers, then in the connection's buffer, which overflows.
      eventually(timeout(60.seconds), interval(500.millis))(demo.counters.slowDropped should be > before)
      socket.close()
      val seen = reader.pushes.size
      eventually(timeout(5.seconds))(reader.pushes.size should be > seen)
      reader.close()
    }
  }

  private def handshake(socket: Socket): Unit = {
    val request = s"GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n" +
      "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
    socket.getOutputStream.write(request.getBytes(StandardCharsets.US_ASCII))
    socket.getOutputStream.flush()
  }

  /** A raw socket past the WebSocket handshake (its response headers read). */
  private def upgraded(): Socket = {
    val socket = new Socket("127.0.0.1", demo.address.getPort)
    socket.setSoTimeout(10000)
    handshake(socket)
    val in = socket.getInputStream
    val head = new ByteArrayOutputStream
    while (!head.toString(StandardCharsets.US_ASCII).endsWith("\r\n\r\n")) {
      val b = in.read()
      if (b < 0) fail("the server closed during the handshake")
      head.write(b)
    }
    head.toString(StandardCharsets.US_ASCII) should startWith("HTTP/1.1 101")
    socket
  }

  /** Bytes read until the server closes (or `limit`). */
  private def drain(in: InputStream, limit: Int): Int = {
    val buffer = new Array[Byte](4096)
    var total = 0
    var n = 0
    while (n >= 0 && total < limit) {
      n = Try(in.read(buffer)).getOrElse(-1)
      if (n > 0) total += n
    }
    total
  }

}
