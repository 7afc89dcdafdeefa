package apps.datagram

import java.net.{InetSocketAddress, SocketTimeoutException}
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.actor.typed.ActorRef
import com.typesafe.config.ConfigFactory
import org.scalatest.wordspec.AnyWordSpecLike

import apps.zeromq.EndpointClient.{decode, request}
import apps.zeromq.StubRobots
import naogateway.wire.{MessageContents, RpcReply, RpcValue}

/** The datagram door through real UDP sockets on loopback, in front of the ZeroMQ specs' scripted robots. */
class DatagramDoorSpec
    extends ScalaTestWithActorTestKit(ConfigFactory.parseString(
        """apps.datagram-door.port = 0
          |# A port loop of the spec's own: the door's socket read on the thread that runs this dispatcher's actors.
          |door-loop {
          |  type = Dispatcher
          |  executor = "naogateway.transport.PortLoopConfigurator"
          |  port-loop { datagrams-per-pass = 256, tasks-per-pass = 64 }
          |  throughput = 64
          |}
          |""".stripMargin).withFallback(ConfigFactory.load()))
    with AnyWordSpecLike
    with LogCapturing {

  private val settings = DatagramDoorSettings(system).copy(requestTimeout = 10.seconds)

  /** A door of the test's own in front of `robots`, with `settings` changed by `change`; its ref and address. */
  private def door(robots: robotmiddleware.RobotInterface,
      change: DatagramDoorSettings => DatagramDoorSettings = identity)
      : (ActorRef[DatagramDoor.Command], InetSocketAddress) = {
    val ref = spawn(DatagramDoor.withInterface(robots, change(settings)))
    val probe = createTestProbe[InetSocketAddress]()
    ref ! DatagramDoor.GetAddress(probe.ref)
    ref -> probe.receiveMessage(5.seconds)
  }

  private def stats(ref: ActorRef[DatagramDoor.Command]): DatagramDoor.Stats = {
    val probe = createTestProbe[DatagramDoor.Stats]()
    ref ! DatagramDoor.GetStats(probe.ref)
    probe.receiveMessage(5.seconds)
  }

  /** A client socket on loopback, with a receive deadline. */
  private final class Client(door: InetSocketAddress) extends AutoCloseable {
    private val channel = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
    channel.connect(door)

    def send(bytes: Array[Byte]): Unit = { channel.write(ByteBuffer.wrap(bytes)); () }

    /** The next reply, or None when none came within `within`. */
    def receive(within: FiniteDuration = 5.seconds): Option[(MessageContents, RpcReply)] = {
      val socket = channel.socket()
      socket.setSoTimeout(within.toMillis.toInt)
      val packet = new java.net.DatagramPacket(new Array[Byte](65536), 65536)
      try {
        socket.receive(packet)
        Some(decode(java.util.Arrays.copyOf(packet.getData, packet.getLength)))
      } catch { case _: SocketTimeoutException => None }
    }

    def ask(bytes: Array[Byte]): (MessageContents, RpcReply) = {
      send(bytes)
      receive().getOrElse(fail("no reply within 5 s"))
    }

    def close(): Unit = channel.close()
  }

  private def dropped(ref: ActorRef[DatagramDoor.Command], kind: DatagramDoor.Drop): Long = stats(ref).dropped(kind)

  "The datagram door" must {
    "answer requests with the ZeroMQ endpoint's replies, the callId echoed, to the sender's address" in {
      val stub = new StubRobots(system)
      val (ref, address) = door(stub)
      address.getAddress.getHostAddress shouldBe "127.0.0.1"
      address.getPort should be > 0
      val client = new Client(address)
      try {
        val (contents, reply) = client.ask(request(7, "speech", "say", Vector(RpcValue.Text("hello")), callId = 41))
        contents.robotId shouldBe 7
        reply.callId shouldBe Some(41L)
        reply.result shouldBe Right(Some(RpcValue.Flag(true)))
        val (_, robots) = client.ask(request(-1, "gateway", "robots", callId = 42))
        robots.result shouldBe Right(Some(RpcValue.Items(Vector(RpcValue.UInt(7), RpcValue.UInt(8)))))
        val (_, offline) = client.ask(request(8, "motion", "stop", callId = 43))
        offline.callId shouldBe Some(43L)
        offline.result.left.toOption.get should startWith("offline: ")
        val (_, malformed) = client.ask(request(7, "motion", "walk", Vector(RpcValue.Text("fast")), callId = 44))
        malformed.result.left.toOption.get should startWith("malformed request: motion.walk takes 3 number(s)")
        // A read takes no lease: robot 9's walk is the referee's (the stub refuses its lease), its posture is anyone's.
        val (_, read) = client.ask(request(9, "motion", "getPosture", callId = 45))
        read.result shouldBe Right(Some(RpcValue.Text("9:motion.getPosture()")))
        stub.seen should contain("say hello 7")
        stub.seen.filter(_.startsWith("acquire 9")) shouldBe empty
        stats(ref).accepted shouldBe 5
        stats(ref).dropped.values.sum shouldBe 0
      } finally client.close()
      testKit.stop(ref)
    }

    "drop oversize and unreadable datagrams without a reply, count each by kind, and serve on" in {
      val stub = new StubRobots(system)
      val (ref, address) = door(stub, _.copy(maxDatagramBytes = 256))
      val client = new Client(address)
      try {
        client.send(Array.fill[Byte](257)(8))
        client.send(Array.fill[Byte](5000)(8))
        client.send("not a protobuf message".getBytes("UTF-8"))
        // A Message without an rpcRequest: readable protobuf, but not a request.
        client.send(MessageContents(7).toProtobuf)
        client.receive(300.millis) shouldBe None
        eventually {
          dropped(ref, DatagramDoor.Drop.Oversize) shouldBe 2
          dropped(ref, DatagramDoor.Drop.Unreadable) shouldBe 2
        }
        // A request of exactly the largest size is read.
        val padded = request(7, "speech", "say", Vector(RpcValue.Text("x" * 200)), callId = 5)
        padded.length should be <= 256
        client.ask(padded)._2.result shouldBe Right(Some(RpcValue.Flag(true)))
        stats(ref).accepted shouldBe 1
      } finally client.close()
      testKit.stop(ref)
    }

    "drop requests over the cap per sender and in all, counted by kind, and answer the ones it took" in {
      val stub = new StubRobots(system)
      val (ref, address) = door(stub, _.copy(maxInFlight = 3, maxInFlightPerSender = 2))
      val first = new Client(address)
      val second = new Client(address)
      try {
        // Robot 14 answers only when the test says so: its requests stay in flight.
        (1 to 3).foreach(i =>
          first.send(request(14, "speech", "say", Vector(RpcValue.Text(s"a$i")), callId = i.toLong)))
        eventually(dropped(ref, DatagramDoor.Drop.SenderOverloaded) shouldBe 1)
        (4 to 5).foreach(i =>
          second.send(request(14, "speech", "say", Vector(RpcValue.Text(s"b$i")), callId = i.toLong)))
        eventually(dropped(ref, DatagramDoor.Drop.Overloaded) shouldBe 1)
        stats(ref).accepted shouldBe 3
        first.receive(200.millis) shouldBe None
        stub.robot14Answers.success(())
        val firstIds = Vector(first.receive(), first.receive()).flatten.map(_._2.callId.get).toSet
        firstIds shouldBe Set(1L, 2L)
        second.receive().map(_._2.callId) shouldBe Some(Some(4L))
        first.receive(300.millis) shouldBe None
        second.receive(100.millis) shouldBe None
        // With the requests answered the cap is free again.
        first.ask(request(7, "speech", "say", Vector(RpcValue.Text("again")), callId = 9))._2.callId shouldBe Some(9L)
      } finally { first.close(); second.close() }
      testKit.stop(ref)
    }

    "answer a request the robots do not answer in time with a timeout, once" in {
      val stub = new StubRobots(system)
      val (ref, address) = door(stub, _.copy(requestTimeout = 300.millis))
      val client = new Client(address)
      try {
        val (_, reply) = client.ask(request(14, "motion", "stop", callId = 3))
        reply.callId shouldBe Some(3L)
        reply.result.left.toOption.get should startWith("timeout: no answer to motion.stop within 300 ms")
        stub.robot14Answers.success(())
        client.receive(300.millis) shouldBe None
      } finally client.close()
      testKit.stop(ref)
    }

    "answer what is pending when it stops, close its socket and end its reader" in {
      val stub = new StubRobots(system)
      val (ref, address) = door(stub)
      val client = new Client(address)
      try {
        client.send(request(14, "speech", "say", Vector(RpcValue.Text("late")), callId = 6))
        eventually(stats(ref).accepted shouldBe 1)
        testKit.stop(ref)
        val (_, reply) = client.receive().getOrElse(fail("no reply at shutdown"))
        reply.result shouldBe Left("endpoint error: the datagram door is shutting down")
        eventually {
          Thread.getAllStackTraces.keySet.asScala.exists(t =>
            t.isAlive && t.getName.endsWith(DatagramDoor.ReaderName)) shouldBe false
          // The port is free again: the socket is closed.
          val again = DatagramChannel.open()
          try again.bind(address)
          finally again.close()
        }
      } finally client.close()
    }

    "read its socket on the port loop of the dispatcher it names, with no reader thread of its own" in {
      val stub = new StubRobots(system)
      val (ref, address) = door(stub, _.copy(dispatcher = "door-loop"))
      val client = new Client(address)
      try {
        client.ask(request(7, "speech", "say", Vector(RpcValue.Text("on the loop")), callId = 51))._2.result shouldBe
          Right(Some(RpcValue.Flag(true)))
        stub.seen should contain("say on the loop 7")
        // A door that could not attach falls back to a reader thread of its own, named after the door.
        eventually {
          val alive = Thread.getAllStackTraces.keySet.asScala.filter(_.isAlive).map(_.getName)
          alive.exists(_.endsWith(DatagramDoor.ReaderName)) shouldBe false
          alive.exists(_.contains("door-loop")) shouldBe true
        }
      } finally client.close()
      testKit.stop(ref)
      // Detached from the loop when it stops: the port is free again.
      eventually {
        val again = DatagramChannel.open()
        try again.bind(address)
        finally again.close()
      }
    }
  }

  "DatagramDoorSettings" must {
    "refuse bounds that cannot work" in {
      an[IllegalArgumentException] should be thrownBy settings.copy(maxInFlightPerSender = settings.maxInFlight + 1)
      an[IllegalArgumentException] should be thrownBy settings.copy(maxDatagramBytes = 65508)
      an[IllegalArgumentException] should be thrownBy settings.copy(port = 70000)
      settings.bindAddress shouldBe "127.0.0.1"
    }
  }
}
