package apps.zeromq

import java.nio.charset.StandardCharsets
import java.util.concurrent.Executors

import scala.concurrent.duration._
import scala.concurrent.{Await, ExecutionContext, Future}
import scala.jdk.CollectionConverters._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.actor.typed.{ActorRef, ActorSystem}
import akka.actor.typed.scaladsl.AskPattern._
import akka.actor.typed.scaladsl.Behaviors
import com.google.protobuf.CodedOutputStream
import com.typesafe.config.ConfigFactory
import org.scalatest.BeforeAndAfterAll
import org.scalatest.wordspec.AnyWordSpecLike
import org.zeromq.{SocketType, ZContext, ZMQ, ZMsg}

import naogateway.wire.gamecontroller.{GameControllerCodec, GameState}
import naogateway.wire.{HaViMo, MessageContents, Posture, RpcCall, RpcReply, RpcValue}

/** Requests and replies as a client sees them. */
object EndpointClient {

  /** Readies a jeromq client socket: jeromq 0.6.0 clients stall in the ZeroMQ handshake after about 1 in 100 connects
    * (libzmq clients, e.g. pyzmq, do not); a short handshake interval makes them connect again.
    */
  def readyClient(socket: ZMQ.Socket): Unit = { socket.setHandshakeIvl(300); () }

  /** The body of a request for `module.method(params)` on `robotId` with `callId`. */
  def request(robotId: Int, module: String, method: String, params: Vector[RpcValue] = Vector.empty, callId: Long = 1L)
      : Array[Byte] =
    MessageContents(robotId, rpcRequest = Some(RpcCall(module, method, params, Some(callId)).toProto)).toProtobuf

  /** The contents and the RPC reply of a reply body. */
  def decode(body: Array[Byte]): (MessageContents, RpcReply) = {
    val contents = MessageContents.parse(body).fold(e => throw new AssertionError(e.describe), identity)
    contents -> RpcReply.fromProto(
      contents.rpcResponse.getOrElse(throw new AssertionError("reply without rpcResponse")))
  }

  /** Sends one request on a DEALER (with the REQ-style empty delimiter) and waits for one reply. */
  def ask(socket: ZMQ.Socket, body: Array[Byte], within: FiniteDuration = 5.seconds): (MessageContents, RpcReply) = {
    socket.send(Array.emptyByteArray, ZMQ.SNDMORE)
    socket.send(body, 0)
    decode(receive(socket, within).last)
  }

  /** The frames of the next message, failing after `within`. */
  def receive(socket: ZMQ.Socket, within: FiniteDuration): Vector[Array[Byte]] = {
    socket.setReceiveTimeOut(within.toMillis.toInt)
    val message = ZMsg.recvMsg(socket)
    if (message == null) throw new AssertionError(s"no message within $within")
    message.asScala.map(_.getData).toVector
  }
}

class ZeroMqEndpointSpec
    extends ScalaTestWithActorTestKit(
      ConfigFactory
        // Two threads: the spec's endpoint and the one a test starts and stops beside it (one loop each). The request
        // timeout is generous: on a loaded machine a request of the concurrency test may wait seconds for its turn, and
        // the timeout test brings an endpoint of its own with a short one.
        .parseString("apps.zeromq { request-timeout = 10s, dispatcher.thread-pool-executor.fixed-pool-size = 2 }")
        .withFallback(ConfigFactory.load())
    )
    with AnyWordSpecLike
    with LogCapturing
    with BeforeAndAfterAll {
  import EndpointClient._

  private val settings = ZeroMqSettings(system).copy(bind = "tcp://127.0.0.1:*", publish = "tcp://127.0.0.1:*")
  private val stub = new StubRobots(system)
  private lazy val endpoint = spawn(ZeroMqEndpoint.withInterface(stub, settings), "endpoint")
  private lazy val addresses = {
    val probe = createTestProbe[ZeroMqEndpoint.Addresses]()
    endpoint ! ZeroMqEndpoint.GetAddresses(probe.ref)
    probe.receiveMessage(5.seconds)
  }
  private val zeroMq = new ZContext()
  private val threads = Executors.newFixedThreadPool(8)
  private implicit val threadPool: ExecutionContext = ExecutionContext.fromExecutor(threads)

  override protected def afterAll(): Unit = {
    threads.shutdownNow()
    zeroMq.close()
    super.afterAll()
  }

  private def dealer(): ZMQ.Socket = {
    val s = zeroMq.createSocket(SocketType.DEALER)
    s.setLinger(0)
    readyClient(s)
    s.connect(addresses.requests)
    s
  }

  private def askOne(robotId: Int, module: String, method: String, params: RpcValue*): RpcReply = {
    val s = dealer()
    try {
      val (contents, reply) = ask(s, request(robotId, module, method, params.toVector, callId = 77))
      contents.robotId shouldBe robotId
      reply.callId shouldBe Some(77L)
      reply
    } finally s.close()
  }

  private def error(reply: RpcReply): String = reply.result.left.getOrElse(fail(s"expected an error, got $reply"))

  private def loopThreads(prefix: String): Set[String] =
    Thread.getAllStackTraces.keySet.asScala.filter(t =>
      t.isAlive && t.getName.startsWith(prefix) &&
        t.getName.endsWith(ZeroMqEndpoint.LoopName)).map(_.getName).toSet

  private def port(endpoint: String): Int = {
    endpoint should fullyMatch regex """tcp://127\.0\.0\.1:[0-9]+"""
    endpoint.substring(endpoint.lastIndexOf(':') + 1).toInt
  }

  /** An endpoint of the test's own, on free ports, with `settings` changed by `change`; its addresses. */
  private def ownEndpoint(robots: robotmiddleware.RobotInterface, change: ZeroMqSettings => ZeroMqSettings = identity)
      : (ActorRef[ZeroMqEndpoint.Command], ZeroMqEndpoint.Addresses) = {
    val own = spawn(ZeroMqEndpoint.withInterface(robots, change(settings)))
    val probe = createTestProbe[ZeroMqEndpoint.Addresses]()
    own ! ZeroMqEndpoint.GetAddresses(probe.ref)
    own -> probe.receiveMessage(10.seconds)
  }

  "EndpointProtocol" must {
    "write the worked examples of docs/zeromq.md" in {
      val doc = new String(java.nio.file.Files.readAllBytes(new java.io.File(PythonEnv.root, "docs/zeromq.md").toPath),
        StandardCharsets.UTF_8)
      def example(name: String): String = {
        val start = doc.indexOf(s"<!-- example: $name -->")
        start should be >= 0
        val block = doc.indexOf("```hex", start) + "```hex".length
        doc.substring(block, doc.indexOf("```", block)).trim.split("\\s+").mkString(" ")
      }
      def hex(bytes: Array[Byte]): String = bytes.map(b => f"${b & 0xff}%02X").mkString(" ")
      hex(request(20, "motion", "posture", Vector(RpcValue.Text("stand")), callId = 1)) shouldBe example("zmq-request")
      hex(EndpointProtocol.reply(20, Some(1L), Right(Answer(Some(RpcValue.Text("stand")))))) shouldBe example(
        "zmq-reply")
      EndpointProtocol.parse(request(20, "motion", "posture", Vector(RpcValue.Text("stand")), callId = 1))
        .flatMap(r => EndpointProtocol.route(r).left.map(e => Unreadable(20, None, e))) shouldBe
        Right(Route.Execute(20, robotmiddleware.Operation.Posture(Posture.Stand)))
    }
  }

  "EndpointProtocol's subscription match" must {
    "take a topic as ZeroMQ does, by prefix, the empty prefix every topic, and nothing without a subscriber" in {
      EndpointProtocol.subscribed(Set.empty, EndpointProtocol.statusTopic(3)) shouldBe false
      EndpointProtocol.subscribed(Set(""), EndpointProtocol.GameTopic) shouldBe true
      EndpointProtocol.subscribed(Set("status."), EndpointProtocol.statusTopic(3)) shouldBe true
      EndpointProtocol.subscribed(Set("status.3"), EndpointProtocol.statusTopic(3)) shouldBe true
      EndpointProtocol.subscribed(Set("status.4"), EndpointProtocol.statusTopic(3)) shouldBe false
      EndpointProtocol.subscribed(Set("vision"), EndpointProtocol.GameTopic) shouldBe false
    }
  }

  "The ZeroMQ endpoint" must {
    "answer many concurrent clients, each exactly its own replies, in the framing each used" in {
      val perClient = 40
      val dealers = (1 to 6).map { client =>
        Future {
          val s = dealer()
          try {
            val delimited = client % 2 == 0
            val sent = (1 to perClient).map { i =>
              val callId = client * 1000L + i
              if (delimited) s.send(Array.emptyByteArray, ZMQ.SNDMORE)
              s.send(request(7, "echo", "call", Vector(RpcValue.Text(s"c$client-$i")), callId), 0)
              callId -> s"7:echo.call(Text(c$client-$i))"
            }.toMap
            val received = (1 to perClient).map { _ =>
              val frames = receive(s, 10.seconds)
              // A delimited request gets a delimited reply; a bare one a bare reply.
              frames.length shouldBe (if (delimited) 2 else 1)
              val (_, reply) = decode(frames.last)
              reply.callId.get -> reply.result
            }
            received.map(_._1).distinct.size shouldBe perClient
            received.foreach { case (id, result) => result shouldBe Right(Some(RpcValue.Text(sent(id)))) }
            s.setReceiveTimeOut(200)
            s.recv(0) shouldBe null // nothing more: each request was answered exactly once
            perClient
          } finally s.close()
        }
      }
      val reqs = (1 to 2).map { client =>
        Future {
          val s = zeroMq.createSocket(SocketType.REQ)
          s.setLinger(0)
          readyClient(s)
          s.setReceiveTimeOut(10000)
          s.connect(addresses.requests)
          try {
            (1 to 20).foreach { i =>
              s.send(request(7, "speech", "say", Vector(RpcValue.Text(s"r$client-$i")), callId = i.toLong), 0)
              val (_, reply) = decode(s.recv(0))
              reply shouldBe RpcReply(Right(Some(RpcValue.Flag(true))), Some(i.toLong))
            }
            20
          } finally s.close()
        }
      }
      Await.result(Future.sequence(dealers ++ reqs), 30.seconds).sum shouldBe 6 * perClient + 2 * 20
    }

    "answer malformed requests with an error naming the cause, and keep serving" in {
      val s = dealer()
      try {
        val (c1, r1) = ask(s, Array[Byte](0xff.toByte, 0xff.toByte, 0x01, 0x02))
        error(r1) should startWith("malformed request: not a protobuf Message")
        r1.callId shouldBe None
        c1.robotId shouldBe -1

        val (c2, r2) = ask(s, MessageContents(7).toProtobuf)
        error(r2) shouldBe "malformed request: the Message carries no rpcRequest (extension 7110)"
        c2.robotId shouldBe 7

        // A Request without its required method: still answered, with the call id it carried.
        val inner = {
          val out = new java.io.ByteArrayOutputStream()
          val coded = CodedOutputStream.newInstance(out)
          coded.writeString(1, "motion")
          coded.writeUInt32(15, 42)
          coded.flush()
          out.toByteArray
        }
        val noMethod = {
          val out = new java.io.ByteArrayOutputStream()
          val coded = CodedOutputStream.newInstance(out)
          coded.writeInt32(1, 7)
          coded.writeByteArray(MessageContents.RpcRequestField, inner)
          coded.flush()
          out.toByteArray
        }
        val (c3, r3) = ask(s, noMethod)
        error(r3) should startWith("malformed request:")
        r3.callId shouldBe Some(42L)
        c3.robotId shouldBe 7

        s.send(Array.emptyByteArray, ZMQ.SNDMORE)
        s.send(request(7, "speech", "say"), ZMQ.SNDMORE)
        s.send(Array[Byte](1), 0)
        error(decode(receive(s, 5.seconds).last)._2) shouldBe "malformed request: expected one body frame, got 2"

        error(ask(s, request(7, "motion", "walk", Vector(RpcValue.Number(0.1f), RpcValue.Number(0f))))._2) shouldBe
          "malformed request: motion.walk takes 3 number(s) (vx, vy, omega), got (number, number)"
        error(ask(s, request(7, "motion", "posture", Vector(RpcValue.Text("dance"))))._2) shouldBe
          "malformed request: unknown posture 'dance' (sit, stand, crouch)"

        ask(s, request(7, "speech", "say", Vector(RpcValue.Text("still here")), callId = 5))._2 shouldBe
          RpcReply(Right(Some(RpcValue.Flag(true))), Some(5L))
      } finally s.close()
    }

    "map robot calls onto RobotInterface, taking the lease each needs on the clients' behalf" in {
      stub.calls.clear()
      askOne(7, "motion", "walk", RpcValue.Number(0.1f), RpcValue.Number(0f), RpcValue.Number(0.2f)).result shouldBe
        Right(Some(RpcValue.Flag(true)))
      askOne(7, "motion", "posture", RpcValue.Text("stand")).result shouldBe Right(Some(RpcValue.Text("stand")))
      askOne(7, "motion", "head", RpcValue.Number(0.5f), RpcValue.UInt(0)).result shouldBe Right(
        Some(RpcValue.Flag(true)))
      askOne(7, "speech", "say", RpcValue.Text("hello")).result shouldBe Right(Some(RpcValue.Flag(true)))
      askOne(7, "motion", "stop").result shouldBe Right(Some(RpcValue.Flag(true)))
      askOne(7, "system", "battery").result shouldBe Right(Some(RpcValue.Text("7:system.battery()")))
      stub.seen shouldBe Vector(
        "acquire 7 walk",
        "walk 0.1 0.0 0.2 7",
        "acquire 7 walk",
        "posture stand 7",
        "acquire 7 head",
        "head 0.5 0.0 7",
        "acquire 7 speech",
        "say hello 7",
        "acquire 7 walk",
        "stop 7",
        "call system.battery 7"
      )
    }

    "send through gateway.send: accepted, in order with calls, refused and malformed as a call is" in {
      stub.calls.clear()
      val s = dealer()
      try {
        // Three requests on one socket without waiting: the interface sees them in the order they came.
        val bodies = Vector(
          request(7, "gateway", "send", Vector(RpcValue.Text("speech"), RpcValue.Text("say"), RpcValue.Text("first")),
            callId = 1),
          request(7, "speech", "say", Vector(RpcValue.Text("second")), callId = 2),
          request(7, "gateway", "send",
            Vector(RpcValue.Text("motion"), RpcValue.Text("head"), RpcValue.Number(0.5f),
              RpcValue.Number(0f)), callId = 3)
        )
        bodies.foreach { b => s.send(Array.emptyByteArray, ZMQ.SNDMORE); s.send(b, 0) }
        val replies = (1 to 3).map(_ => decode(receive(s, 5.seconds).last)._2).sortBy(_.callId)
        replies.map(_.result) shouldBe Vector.fill(3)(Right(Some(RpcValue.Flag(true))))
      } finally s.close()
      stub.seen shouldBe Vector("acquire 7 speech", "send speech.say 7", "acquire 7 speech", "say second 7",
        "acquire 7 head", "send motion.head 7")
      error(askOne(9, "gateway", "send", RpcValue.Text("motion"), RpcValue.Text("stop"))) shouldBe
        "lease: lease 'walk' of robot 9 is not held by this app (held by referee)"
      error(askOne(8, "gateway", "send", RpcValue.Text("system"), RpcValue.Text("battery"))) shouldBe
        "offline: robot 8 is offline"
      error(askOne(7, "gateway", "send")) should startWith(
        "malformed request: gateway.send takes the robot call's module")
      error(askOne(7, "gateway", "send", RpcValue.Text("gateway"), RpcValue.Text("robots"))) should startWith(
        "malformed request: gateway.send takes")
      val fast = askOne(7, "gateway", "send", RpcValue.Text("motion"), RpcValue.Text("walk"), RpcValue.Text("fast"))
      error(fast) should startWith(
        "malformed request: motion.walk takes 3 number(s)")
    }

    "serve its own methods: robots, status, acquire and release" in {
      askOne(-1, "gateway", "robots").result shouldBe Right(Some(RpcValue.Items(Vector(RpcValue.UInt(7),
              RpcValue.UInt(8)))))
      val s = dealer()
      val leasesBefore = stub.seen.count(_.startsWith("acquire 7"))
      try {
        val (contents, reply) = ask(s, request(7, "gateway", "status"))
        reply.result shouldBe Right(Some(RpcValue.Items(Vector(RpcValue.Flag(true), RpcValue.Text("good")))))
        contents.robotHealth.flatMap(_.batteryVoltage).get shouldBe 12.3f
        // The robot's own answer to getPosture (a read, no lease taken), not the older keep-alive's `stand`.
        contents.robotHealth.flatMap(_.posture) shouldBe Some("sit")
        contents.status.flatMap(_.activeRole) shouldBe Some("striker")
      } finally s.close()
      stub.seen should contain("call motion.getPosture 7")
      stub.seen.count(_.startsWith("acquire 7")) shouldBe leasesBefore
      askOne(8, "gateway", "status").result shouldBe Right(Some(RpcValue.Items(Vector(RpcValue.Flag(false),
              RpcValue.Text("offline")))))
      error(askOne(99, "gateway", "status")) shouldBe "unknown robot: no robot 99 is known"
      stub.calls.clear()
      askOne(7, "gateway", "acquire", RpcValue.Text("head"), RpcValue.Text("arms")).result shouldBe Right(
        Some(RpcValue.Flag(true)))
      askOne(7, "gateway", "release", RpcValue.Text("head")).result shouldBe Right(Some(RpcValue.Flag(true)))
      stub.seen shouldBe Vector("acquire 7 head,arms", "release 7 head")
      error(askOne(7, "gateway", "acquire", RpcValue.Text("legs"))) should startWith(
        "malformed request: unknown actuator group 'legs'")
      error(askOne(7, "gateway", "reboot")) shouldBe "unknown method: gateway.reboot"
    }

    "name the cause of every failure: unknown robot, offline, lease, rule, timeout, robot error, safety" in {
      def walkError(robotId: Int) =
        error(askOne(robotId, "motion", "walk", RpcValue.Number(0.1f), RpcValue.Number(0f), RpcValue.Number(0f)))
      walkError(99) shouldBe "unknown robot: no robot 99 is known"
      walkError(8) shouldBe "offline: robot 8 is offline"
      walkError(9) shouldBe "lease: lease 'walk' of robot 9 is not held by this app (held by referee)"
      // Reads need no lease: robot 9, whose walk the referee holds, answers them all the same.
      askOne(9, "motion", "getPosture").result shouldBe Right(Some(RpcValue.Text("9:motion.getPosture()")))
      askOne(9, "system", "battery").result shouldBe Right(Some(RpcValue.Text("9:system.battery()")))
      walkError(10) should startWith("rule: competition rule: the base station must not send")
      walkError(11) should startWith("timeout: robot 11 did not answer")
      walkError(12) shouldBe "robot error: not standing: sit"
      walkError(13) should startWith("safety: robot 13 is held safe: battery low")
    }

    "answer a request the robots do not answer in time once, with a timeout, and drop the late answer" in {
      // Robot 14 answers only when the test lets it, after the timeout reply: the order does not depend on timing.
      val (own, addresses) = ownEndpoint(stub, _.copy(requestTimeout = 300.millis))
      val s = zeroMq.createSocket(SocketType.DEALER)
      s.setLinger(0)
      readyClient(s)
      s.connect(addresses.requests)
      try {
        val (_, reply) = ask(s, request(14, "motion", "stop", callId = 3), within = 10.seconds)
        reply shouldBe RpcReply(Left("timeout: no answer to motion.stop within 300 ms at the endpoint"), Some(3L))
        stub.robot14Answers.success(())
        s.setReceiveTimeOut(1000)
        s.recv(0) shouldBe null
      } finally {
        s.close()
        testKit.stop(own, 5.seconds)
      }
    }

    "publish status and game to their subscribers, and a robot's vision only while someone subscribes to it" in {
      val sub = zeroMq.createSocket(SocketType.SUB)
      sub.setLinger(0)
      readyClient(sub)
      sub.connect(addresses.publish)
      try {
        sub.subscribe("status.7".getBytes(StandardCharsets.UTF_8))
        sub.subscribe("game".getBytes(StandardCharsets.UTF_8))
        var topics = Map.empty[String, Vector[Array[Byte]]]
        val deadline = System.nanoTime() + 5.seconds.toNanos
        while (topics.size < 2 && System.nanoTime() < deadline) {
          val frames = receive(sub, 5.seconds)
          topics = topics.updated(new String(frames.head, StandardCharsets.UTF_8), frames)
        }
        val status = topics("status.7")
        val contents = MessageContents.parse(status(1)).fold(e => fail(e.describe), identity)
        contents.robotId shouldBe 7
        contents.robotHealth.flatMap(_.batteryVoltage) shouldBe Some(12.3f)
        contents.status.flatMap(_.currentState) shouldBe Some("stand")
        new String(status(2), StandardCharsets.UTF_8) shouldBe "good"
        topics("game")(1) shouldBe StubRobots.gamePacket
        GameControllerCodec.decodeControl(topics("game")(1)).map(_.gameState) shouldBe Right(GameState.Playing)

        // The robot is known by now, yet nobody asked for its camera: it stays off.
        stub.visionStarted.get shouldBe 0
        sub.subscribe("vision.7".getBytes(StandardCharsets.UTF_8))
        var vision = Option.empty[Vector[Array[Byte]]]
        while (vision.isEmpty) {
          val frames = receive(sub, 5.seconds)
          if (new String(frames.head, StandardCharsets.UTF_8) == "vision.7") vision = Some(frames)
        }
        val regions = MessageContents.parse(vision.get(1)).toOption.flatMap(_.havimoRegions).get
        regions.frame shouldBe 5
        HaViMo.decodeRegions(regions.records.get.toByteArray).map(_.map(_.pixels)) shouldBe Right(Vector(20))
        stub.visionStarted.get shouldBe 1
        sub.unsubscribe("vision.7".getBytes(StandardCharsets.UTF_8))
        eventually(stub.visionEnded.get shouldBe 1)
      } finally sub.close()
    }

    "close its sockets and end its thread when it stops" in {
      // Free ports the endpoint picks itself: one picked here and bound later could be taken by another process.
      val (own, addresses) = ownEndpoint(new StubRobots(system))
      val requestPort = port(addresses.requests)
      val publishPort = port(addresses.publish)
      testKit.stop(own, 5.seconds)
      eventually(loopThreads(system.name).size shouldBe 1) // only the spec's shared endpoint is left
      val again = new ZContext()
      try {
        again.createSocket(SocketType.ROUTER).bind(s"tcp://127.0.0.1:$requestPort") shouldBe true
        again.createSocket(SocketType.XPUB).bind(s"tcp://127.0.0.1:$publishPort") shouldBe true
      } finally again.close()
    }

    "close its sockets and end its thread when the actor system terminates" in {
      val other = ActorSystem[Nothing](Behaviors.empty, "EndpointShutdown", system.settings.config)
      val endpointRef: ActorRef[ZeroMqEndpoint.Command] =
        other.systemActorOf(ZeroMqEndpoint.withInterface(new StubRobots(other), settings), "endpoint")
      val replies =
        Await.result(endpointRef.ask(ZeroMqEndpoint.GetAddresses(_))(akka.util.Timeout(10.seconds), other.scheduler),
          10.seconds)
      val requestPort = port(replies.requests)
      loopThreads("EndpointShutdown").size shouldBe 1
      other.terminate()
      Await.result(other.whenTerminated, 10.seconds)
      loopThreads("EndpointShutdown") shouldBe empty
      val again = new ZContext()
      try again.createSocket(SocketType.ROUTER).bind(s"tcp://127.0.0.1:$requestPort") shouldBe true
      finally again.close()
    }
  }
}
