package apps.web

import java.nio.{ByteBuffer, ByteOrder}
import java.util.Base64

import scala.concurrent.duration._
import scala.concurrent.Await
import scala.jdk.CollectionConverters._
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.http.scaladsl.Http
import akka.http.scaladsl.model.StatusCodes
import akka.http.scaladsl.model.ws.{BinaryMessage, Message, TextMessage, WebSocketRequest}
import akka.stream.scaladsl.{Flow, Keep, Sink, Source}
import akka.util.ByteString
import com.google.protobuf.DescriptorProtos.FileDescriptorSet
import com.google.protobuf.Descriptors.{Descriptor, FileDescriptor}
import com.google.protobuf.DynamicMessage
import org.scalatest.concurrent.Eventually
import org.scalatest.wordspec.AnyWordSpecLike
import spray.json._

/** The Foxglove-protocol feed as a viewer uses it: server info, the advertised channels with their schemas, a
  * subscription to `/robot/1/status` decoded with the advertised schema alone; and what bad requests get.
  */
class FoxgloveFeedSpec extends ScalaTestWithActorTestKit(WebDemo.config) with AnyWordSpecLike with LogCapturing
    with Eventually {

  private lazy val demo = new WebDemo(system, WebSettings(system))

  override def afterAll(): Unit = {
    Try(demo.stop())
    super.afterAll()
  }

  /** A client speaking foxglove.websocket.v1 that keeps what it gets and sends what it is given. */
  private final class Client(uri: String = s"ws://127.0.0.1:${demo.address.getPort}/foxglove",
      protocol: Option[String] = Some(FoxgloveFeed.Subprotocol)) {
    @volatile var texts = Vector.empty[JsObject]
    @volatile var binaries = Vector.empty[ByteString]
    // A long text (an advertisement of many channels, each with the descriptor set) may come in parts: made whole.
    private val sink = Flow[Message].mapAsync(1) {
      case t: TextMessage   => t.toStrict(10.seconds)
      case b: BinaryMessage => b.toStrict(10.seconds)
    }.toMat(Sink.foreach[Message] {
      case t: TextMessage.Strict   => synchronized { texts :+= t.text.parseJson.asJsObject }
      case b: BinaryMessage.Strict => synchronized { binaries :+= b.data }
      case _                       => ()
    })(Keep.right)
    private val (out, outSource) = Source.queue[Message](16).preMaterialize()
    val (upgrade, done) = Http().singleWebSocketRequest(WebSocketRequest(uri, subprotocol = protocol),
      Flow.fromSinkAndSourceMat(sink, outSource)(Keep.left))
    def status: akka.http.scaladsl.model.StatusCode = Await.result(upgrade, 10.seconds).response.status
    def send(text: String): Unit = out.offer(TextMessage(text))
    def close(): Unit = out.complete()
    def ops(op: String): Vector[JsObject] = texts.filter(_.fields.get("op").contains(JsString(op)))
    def channels: Vector[JsObject] =
      ops("advertise").flatMap(_.fields("channels").asInstanceOf[JsArray].elements.map(_.asJsObject))
  }

  /** The message type `name` of a protobuf FileDescriptorSet, built from the set alone (dependencies first). */
  private def descriptor(set: Array[Byte], name: String): Descriptor = {
    val built = scala.collection.mutable.LinkedHashMap.empty[String, FileDescriptor]
    FileDescriptorSet.parseFrom(set).getFileList.asScala.foreach { f =>
      built(f.getName) = FileDescriptor.buildFrom(f, f.getDependencyList.asScala.map(built).toArray)
    }
    built.values.flatMap(f => Option(f.findMessageTypeByName(name.split('.').last)).filter(_.getFullName == name)).head
  }

  "The Foxglove-protocol feed" should {
    "advertise /robot/<id>/status and /health, and send robot 1's status decodable with the advertised schema" in {
      val client = new Client()
      try {
        client.status shouldBe StatusCodes.SwitchingProtocols
        Await.result(client.upgrade, 10.seconds).response.headers.map(_.value) should contain(FoxgloveFeed.Subprotocol)
        eventually(timeout(30.seconds), interval(200.millis)) {
          client.ops("serverInfo") should have size 1
          client.channels.map(_.fields("topic")) should contain allOf (JsString("/robot/1/status"),
            JsString("/robot/1/health"),
            JsString("/robot/3/status"))
        }
        val channel = client.channels.find(_.fields("topic") == JsString("/robot/1/status")).get
        channel.fields("encoding") shouldBe JsString("protobuf")
        channel.fields("schemaEncoding") shouldBe JsString("protobuf")
        channel.fields("schemaName") shouldBe JsString("naogateway.proto.Status")
        val channelId = channel.fields("id").asInstanceOf[JsNumber].value.toInt
        client.send(s"""{"op":"subscribe","subscriptions":[{"id":7,"channelId":$channelId}]}""")
        eventually(timeout(10.seconds), interval(100.millis))(client.binaries should not be empty)
        val frame = client.binaries.head.toByteBuffer.order(ByteOrder.LITTLE_ENDIAN)
        frame.get() shouldBe 1
        frame.getInt() shouldBe 7
        val nanos = frame.getLong()
        math.abs(nanos / 1000000L - System.currentTimeMillis()) should be < 60000L
        val payload = new Array[Byte](frame.remaining())
        frame.get(payload)
        val schema = Base64.getDecoder.decode(channel.fields("schema").asInstanceOf[JsString].value)
        val status = DynamicMessage.parseFrom(descriptor(schema, "naogateway.proto.Status"), payload)
        val fields = status.getAllFields.asScala.map { case (k, v) => k.getName -> v.toString }
        fields.get("activeRole") shouldBe Some("keeper")
        fields.keySet should contain("currentState")

        // Unsubscribed, the data stops.
        client.send("""{"op":"unsubscribe","subscriptionIds":[7]}""")
        Thread.sleep(500)
        val n = client.binaries.size
        Thread.sleep(1000)
        client.binaries.size shouldBe n
      } finally client.close()
    }

    "advertise /robot/<id>/servos, and send robot 1's servo telemetry decodable with the advertised schema" in {
      val client = new Client()
      try {
        eventually(timeout(30.seconds), interval(200.millis)) {
          client.channels.map(_.fields("topic")) should contain(JsString("/robot/1/servos"))
        }
        val channel = client.channels.find(_.fields("topic") == JsString("/robot/1/servos")).get
        channel.fields("encoding") shouldBe JsString("protobuf")
        channel.fields("schemaName") shouldBe JsString("naogateway.proto.ServoTelemetry")
        val channelId = channel.fields("id").asInstanceOf[JsNumber].value.toInt
        client.send(s"""{"op":"subscribe","subscriptions":[{"id":9,"channelId":$channelId}]}""")
        // The simulated robots send their telemetry once a second.
        eventually(timeout(10.seconds), interval(100.millis))(client.binaries should not be empty)
        val frame = client.binaries.head.toByteBuffer.order(ByteOrder.LITTLE_ENDIAN)
        frame.get() shouldBe 1
        frame.getInt() shouldBe 9
        frame.getLong()
        val payload = new Array[Byte](frame.remaining())
        frame.get(payload)
        val schema = Base64.getDecoder.decode(channel.fields("schema").asInstanceOf[JsString].value)
        val telemetry = DynamicMessage.parseFrom(descriptor(schema, "naogateway.proto.ServoTelemetry"), payload)
        val servos = telemetry.getField(telemetry.getDescriptorForType.findFieldByName("servos"))
          .asInstanceOf[java.util.List[DynamicMessage]].asScala
        servos.size shouldBe 18
        val first = servos.head
        first.getField(first.getDescriptorForType.findFieldByName("id")) shouldBe 1
        val volts = first.getField(first.getDescriptorForType.findFieldByName("voltage")).asInstanceOf[Int]
        volts should (be > 90 and be < 130) // tenths of a volt, as the robot sent them
      } finally client.close()
    }

    "advertise /gateway/decisions as JSON, and send game states and the budget as the recording writes them" in {
      val client = new Client()
      try {
        eventually(timeout(10.seconds), interval(100.millis)) {
          client.channels.map(_.fields("topic")) should contain(JsString("/gateway/decisions"))
        }
        val channel = client.channels.find(_.fields("topic") == JsString("/gateway/decisions")).get
        channel.fields("encoding") shouldBe JsString("json")
        channel.fields("schema") shouldBe JsString("")
        val channelId = channel.fields("id").asInstanceOf[JsNumber].value.toInt
        client.send(s"""{"op":"subscribe","subscriptions":[{"id":9,"channelId":$channelId}]}""")
        // The demo's GameController sends every 100 ms: its packets come as game-state decisions.
        val decisions = eventually(timeout(20.seconds), interval(100.millis)) {
          val decoded = client.binaries.map { b =>
            val frame = b.toByteBuffer.order(ByteOrder.LITTLE_ENDIAN)
            frame.get() shouldBe 1
            frame.getInt() shouldBe 9
            val nanos = frame.getLong()
            val payload = new Array[Byte](frame.remaining())
            frame.get(payload)
            (nanos, new String(payload, java.nio.charset.StandardCharsets.UTF_8).parseJson.asJsObject)
          }
          decoded.map(_._2.fields("decision")) should contain allOf (JsString("game-state"), JsString("budget"))
          decoded
        }
        val (nanos, game) = decisions.find(_._2.fields("decision") == JsString("game-state")).get
        game.fields("gatewayTimeNs") shouldBe JsNumber(nanos)
        game.fields("state").asInstanceOf[JsString].value should not be empty
        game.fields.keySet should contain("version")
        val budget = decisions.map(_._2).find(_.fields("decision") == JsString("budget")).get
        budget.fields("limitBytesPerSecond").asInstanceOf[JsNumber].value.toInt should be > 0
        budget.fields("queued").asJsObject.fields.keySet should not be empty
      } finally client.close()
    }

    "carry /gateway/datagrams and /robot/<id>/message with the recording's schemas, and the send and reply decisions, " +
      "from the gateway's tap while a client is connected" in {
        val client = new Client()
        try {
          eventually(timeout(30.seconds), interval(100.millis)) {
            client.channels.map(_.fields("topic")) should contain allOf (JsString("/gateway/datagrams"),
              JsString("/gateway/decisions"), JsString("/robot/1/message"))
          }
          def channel(topic: String) = client.channels.find(_.fields("topic") == JsString(topic)).get
          val datagrams = channel("/gateway/datagrams")
          datagrams.fields("encoding") shouldBe JsString("protobuf")
          datagrams.fields("schemaName") shouldBe JsString("naogateway.proto.RecordedDatagram")
          val message = channel("/robot/1/message")
          message.fields("schemaName") shouldBe JsString("naogateway.proto.Message")
          val subscriptions = Map(21 -> datagrams, 22 -> channel("/gateway/decisions"), 23 -> message)
          client.send(subscriptions.map { case (id, c) => s"""{"id":$id,"channelId":${c.fields("id")}}""" }
              .mkString("""{"op":"subscribe","subscriptions":[""", ",", "]}"))
          // The gateway's tap is read by the feed now: the readers' figures name it.
          eventually(timeout(10.seconds), interval(100.millis)) {
            Await.result(demo.side.view.stats(), 10.seconds).tap.map(_.reader) should contain(FoxgloveFeed.TapReader)
          }
          // A call to robot 1: the outbox sends it, the robot answers it.
          val app = createTestProbe[robotmiddleware.AppEvent]()
          val registered = createTestProbe[robotmiddleware.RobotMiddleware.AppRegistered]()
          demo.middleware ! robotmiddleware.RobotMiddleware.RegisterApp("feed-spec", 1, app.ref, registered.ref)
          registered.receiveMessage(10.seconds)
          val lease = createTestProbe[robotmiddleware.RobotMiddleware.LeaseResult]()
          demo.middleware ! robotmiddleware.RobotMiddleware.Acquire(app.ref, 1,
            naogateway.wire.ActuatorGroup.Speech: naogateway.wire.ActuatorGroup,
            lease.ref)
          lease.receiveMessage(10.seconds).result.isRight shouldBe true
          val result = createTestProbe[naogateway.api.CallResult]()
          demo.middleware ! robotmiddleware.RobotMiddleware.Execute(app.ref, 1,
            robotmiddleware.Operation.Say("feed"), result.ref)
          val answered = result.receiveMessage(20.seconds)
          withClue(answered)(answered.result.isRight shouldBe true)
          def on(sub: Int): Vector[(Long, Array[Byte])] = client.binaries.flatMap { b =>
            val frame = b.toByteBuffer.order(ByteOrder.LITTLE_ENDIAN)
            frame.get()
            if (frame.getInt() != sub) None
            else {
              val nanos = frame.getLong()
              val payload = new Array[Byte](frame.remaining())
              frame.get(payload)
              Some(nanos -> payload)
            }
          }
          val schema = Base64.getDecoder.decode(datagrams.fields("schema").asInstanceOf[JsString].value)
          eventually(timeout(20.seconds), interval(100.millis)) {
            val recorded = on(21).map(m =>
              DynamicMessage.parseFrom(descriptor(schema, "naogateway.proto.RecordedDatagram"),
                m._2))
            def field(m: DynamicMessage, name: String) = m.getField(m.getDescriptorForType.findFieldByName(name))
            val kinds = recorded.map(m => (field(m, "port").toString, field(m, "direction").toString))
            kinds should contain allOf (("ROBOT_PORT", "RECEIVED"), ("ROBOT_PORT", "SENT"),
              ("GAME_CONTROLLER", "RECEIVED"))
            recorded.filter(m => field(m, "port").toString == "ROBOT_PORT").map(m => field(m, "robotID")) should
              contain(Int.box(1))
            val decisions = on(22).map(m => new String(m._2, "UTF-8").parseJson.asJsObject)
            val send = decisions.filter(_.fields("decision") == JsString("send"))
            send.map(_.fields("robotId")) should contain(JsNumber(1))
            decisions.map(_.fields("decision")) should contain(JsString("reply"))
            val replies = on(23).map(m =>
              DynamicMessage.parseFrom(descriptor(schema, "naogateway.proto.Message"),
                m._2))
            // The robot's answer: a Message with the rpcResponse extension (7111, rpc.proto), whole.
            replies.exists(_.getUnknownFields.hasField(7111)) shouldBe true
          }
        } finally client.close()
        // With the client gone the feed leaves the tap.
        eventually(timeout(10.seconds), interval(100.millis)) {
          Await.result(demo.side.view.stats(), 10.seconds).tap.map(_.reader) should not contain FoxgloveFeed.TapReader
        }
      }

    "answer a subscription to a channel that does not exist and bad requests with an error status, and keep serving" in {
      val client = new Client()
      try {
        eventually(timeout(10.seconds))(client.ops("serverInfo") should have size 1)
        client.send("""{"op":"subscribe","subscriptions":[{"id":1,"channelId":99999}]}""")
        client.send("not json at all \u0000")
        client.send("""{"op":"advertise","channels":[]}""")
        client.send("""{"op":"subscribe","subscriptions":[{"id":"x"}]}""")
        eventually(timeout(10.seconds)) {
          client.ops("status").map(_.fields("message").asInstanceOf[JsString].value) shouldBe Vector(
            "channel 99999 does not exist", "not a JSON object", "operation 'advertise' is not supported",
            "a subscription needs an id and a channelId")
          client.ops("status").map(_.fields("level")).distinct shouldBe Vector(JsNumber(2))
        }
        // A request longer than any real one closes that connection only.
        client.send("[" + "1," * FoxgloveFeed.MaxRequestChars + "1]")
        Await.ready(client.done, 10.seconds).isCompleted shouldBe true
        val other = new Client()
        eventually(timeout(10.seconds))(other.ops("serverInfo") should have size 1)
        other.close()
      } finally client.close()
    }

    "be read by a Python client over websockets, decoding robot 1's status with the advertised schema" in {
      apps.zeromq.PythonEnv.python() // cancels here when Python, venv or the packages cannot be had
      val (code, output) = apps.zeromq.PythonEnv.script("foxglove_status.py",
        Seq(s"ws://127.0.0.1:${demo.address.getPort}/foxglove", "1", "3"), 2.minutes)
      withClue(output.linesIterator.take(30).mkString("\n")) {
        code shouldBe 0
        output should include("op serverInfo")
        output should include regex """channel \d+ /robot/1/status protobuf naogateway.proto.Status"""
        output.linesIterator.count(_.matches("status subscription 1 time \\d+ role keeper state \\w+")) shouldBe 3
      }
    }

    "refuse a client that does not speak the protocol" in {
      new Client(protocol = None).status shouldBe StatusCodes.BadRequest
      new Client(protocol = Some("foxglove.websocket.v2")).status shouldBe StatusCodes.BadRequest
    }

    "answer a client asking for foxglove.sdk.v1 (the Foxglove SDK's name) with that name, and serve it the same feed" in {
      val client = new Client(protocol = Some(FoxgloveFeed.SdkSubprotocol))
      try {
        client.status shouldBe StatusCodes.SwitchingProtocols
        Await.result(client.upgrade, 10.seconds).response.headers.collect {
          case h if h.is("sec-websocket-protocol") => h.value
        } shouldBe Seq(FoxgloveFeed.SdkSubprotocol)
        eventually(timeout(30.seconds), interval(200.millis)) {
          client.ops("serverInfo") should have size 1
          client.channels.map(_.fields("topic")) should contain(JsString("/robot/1/status"))
        }
      } finally client.close()
    }

    "choose the subprotocol a client asked for, the SDK's when it offers both" in {
      FoxgloveFeed.chosen(Seq("foxglove.websocket.v1")) shouldBe Some("foxglove.websocket.v1")
      FoxgloveFeed.chosen(Seq("foxglove.sdk.v1")) shouldBe Some("foxglove.sdk.v1")
      FoxgloveFeed.chosen(Seq("foxglove.websocket.v1", "foxglove.sdk.v1")) shouldBe Some("foxglove.sdk.v1")
      FoxgloveFeed.chosen(Seq("chat", "superchat")) shouldBe None
      FoxgloveFeed.chosen(Nil) shouldBe None
    }

    "have a layout (docs/foxglove-layout.json) that names only topics and fields the feed has" in {
      val layout =
        new String(java.nio.file.Files.readAllBytes(java.nio.file.Paths.get("..", "docs", "foxglove-layout.json")),
          "UTF-8").parseJson.asJsObject
      val configs = layout.fields("configById").asJsObject.fields
      val paths = configs.values.toVector.flatMap { c =>
        val f = c.asJsObject.fields
        f.get("topicPath").toVector ++ f.get("paths").toVector.flatMap(
          _.asInstanceOf[JsArray].elements.map(_.asJsObject.fields("value")))
      }.map(_.asInstanceOf[JsString].value)
      paths should not be empty
      val Path = """/robot/(\d+)/(status|health)(?:\.(\w+))?""".r
      paths.foreach {
        case Path(_, topic, field) =>
          val schema = descriptor(naogateway.gateway.recording.Recording.descriptorSet,
            if (topic == "status") "naogateway.proto.Status" else "naogateway.proto.RobotHealth")
          if (field != null) withClue(field)(schema.findFieldByName(field) should not be null)
        case "/gateway/decisions" => () // JSON without a schema: a raw-messages panel shows it whole
        case other                => fail(s"$other is no topic of the feed")
      }
      // Every panel the layout places is configured.
      val placed = """"(\w+![\w]+)"""".r.findAllMatchIn(layout.fields("layout").compactPrint).map(_.group(1)).toSet
      placed shouldBe configs.keySet
    }

    "read requests totally" in {
      FoxgloveFeed.request(
        """{"op":"subscribe","subscriptions":[{"id":1,"channelId":2},{"id":3,"channelId":4}]}""") shouldBe
        FoxgloveFeed.Subscribe(Vector(1 -> 2, 3 -> 4))
      FoxgloveFeed.request("""{"op":"unsubscribe","subscriptionIds":[1,2]}""") shouldBe FoxgloveFeed.Unsubscribe(
        Vector(1, 2))
      FoxgloveFeed.request("""{"op":"subscribe","subscriptions":[{"id":1e40,"channelId":2}]}""") shouldBe a[
        FoxgloveFeed.Bad]
      FoxgloveFeed.request("""[1,2]""") shouldBe a[FoxgloveFeed.Bad]
      FoxgloveFeed.request("""{"op":1}""") shouldBe a[FoxgloveFeed.Bad]
      FoxgloveFeed.messageData(5, 6L, Array[Byte](9, 8)).toArray shouldBe
        ByteBuffer.allocate(15).order(ByteOrder.LITTLE_ENDIAN).put(1.toByte).putInt(5).putLong(6L).put(Array[Byte](9,
            8)).array()
    }
  }
}
