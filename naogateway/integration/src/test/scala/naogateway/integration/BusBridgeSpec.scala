package naogateway.integration

import java.io.InputStream
import java.net.{InetSocketAddress, ServerSocket, Socket, SocketTimeoutException}
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.{FishingOutcomes, LogCapturing, ScalaTestWithActorTestKit}
import akka.actor.typed.ActorRef
import com.google.protobuf.ByteString
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.api.{BusBridgeClient, RobotOnline}
import naogateway.gateway.{BusBridgeServer, BusBridgeSettings}
import naogateway.proto.BusBridge
import naogateway.sim.{FirmwareSettings, SimulatedRobot, SimulatedRobotSettings}
import naogateway.sim.bus.Ax12
import naogateway.testkit.TestLoopback
import naogateway.wire.{BusBridgeFrame, Dynamixel}
import naogateway.wire.gamecontroller._

/** The bus bridge end to end (docs/protocol.md 6.9): a real gateway, a simulated robot over loopback UDP with its
  * emulated bus behind the secure stream, and a TCP client at the bridge's port: packets out, status bytes back in
  * order, bad packets dropped, one client at a time, the lease holder told, the competition gate closing it; and a
  * busBridge frame sent as a plain datagram dropped by the robot; and what a stranger on another loopback address sends
  * (forged replies, another robot's id, forged stream segments, requests straight to the robot) reaching neither the
  * tool nor the bus.
  */
class BusBridgeSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {
  import Dynamixel._

  private val robotId = 2

  /** A base port whose robot-2 port is free now. */
  private def freeBase(): Int = {
    val s = new ServerSocket(0, 1, java.net.InetAddress.getLoopbackAddress)
    try s.getLocalPort - robotId
    finally s.close()
  }

  private def streamRobot(f: GatewayFixture): (ActorRef[SimulatedRobot.Command], InetSocketAddress) = {
    val started = createTestProbe[SimulatedRobot.StartResult]()
    spawn(SimulatedRobot(
        SimulatedRobotSettings(FirmwareSettings(robotId), f.addresses.robots,
          bindAddress = new InetSocketAddress(TestLoopback.address(), 0), faithfulLink = false)
          .withStream(f.settings.stream),
        Some(started.ref)
      ))
    started.receiveMessage(10.seconds) match {
      case SimulatedRobot.Started(_, ref, address) => ref -> address
      case other                                   => fail(s"robot did not start: $other")
    }
  }

  private def connectTo(port: Int): Socket = {
    val deadline = 20.seconds.fromNow
    var socket: Option[Socket] = None
    while (socket.isEmpty) {
      socket = Try(new Socket("127.0.0.1", port)).toOption
      if (socket.isEmpty) {
        if (deadline.isOverdue()) fail(s"nothing listens at 127.0.0.1:$port")
        Thread.sleep(100)
      }
    }
    socket.get.setSoTimeout(10000)
    socket.get
  }

  /** A client of the bridge at `port` whose ping servo 1 answers: a robot that went offline for a moment on a loaded
    * machine closes its bridge, so a connection is tried again until one answers.
    */
  private def answering(port: Int): Socket = {
    val deadline = 30.seconds.fromNow
    var answered: Option[Socket] = None
    while (answered.isEmpty) {
      val socket = connectTo(port)
      socket.setSoTimeout(3000)
      socket.getOutputStream.write(packet(1, Ping, Nil))
      if (Try(socket.getInputStream.readNBytes(6).toVector).toOption.contains(packet(1, 0, Nil).toVector)) {
        socket.setSoTimeout(10000)
        answered = Some(socket)
      } else {
        socket.close()
        if (deadline.isOverdue()) fail(s"the bridge at $port never answered a ping")
        Thread.sleep(200)
      }
    }
    answered.get
  }

  private def readStatus(in: InputStream, bytes: Int): Status = {
    val buffer = in.readNBytes(bytes)
    Dynamixel.status(buffer).getOrElse(fail(s"not a status packet: ${buffer.toSeq}"))
  }

  "the bus bridge" must {
    "carry the DynamixelSDK's packets to the robot's bus and its status packets back, one client at a time" in {
      val f = new GatewayFixture(testKit, BusBridgeSpec.Patient)
      val leases = createTestProbe[BusBridgeClient]()
      val base = freeBase()
      val bridge =
        spawn(BusBridgeServer(f.gateway, BusBridgeSettings(enabled = true, basePort = base), Some(leases.ref)))
      try {
        val (robot, address) = streamRobot(f)
        f.awaitEvent(10.seconds) { case RobotOnline(`robotId`, _) => () }
        val client = answering(base + robotId)
        leases.fishForMessage(10.seconds) {
          case BusBridgeClient(`robotId`, true) => FishingOutcomes.complete
          case _                                => FishingOutcomes.continueAndIgnore
        }
        val out = client.getOutputStream
        val in = client.getInputStream
        // Noise before the header, a packet with a bad checksum (dropped, nothing comes back), then a ping.
        val bad = packet(5, Ping, Nil)
        bad(bad.length - 1) = (bad.last ^ 1).toByte
        out.write(Array[Byte](0x13, 0x37) ++ bad ++ packet(5, Ping, Nil))
        readStatus(in, 6) shouldBe Status(5, 0, Vector.empty)
        // A request split over two writes, and two requests in one: the replies come back whole and in order.
        val read = packet(7, Read, Seq(Ax12.ModelNumber, 2))
        out.write(read.take(3)); out.flush(); Thread.sleep(50); out.write(read.drop(3) ++ packet(8, Ping, Nil))
        readStatus(in, 8).params shouldBe Vector(12, 0)
        readStatus(in, 6).id shouldBe 8
        // A goal position written reads back as the present position once the servo got there.
        out.write(packet(robotId, Write, Seq(Ax12.MovingSpeed, 0, 0)))
        readStatus(in, 6).error shouldBe 0
        out.write(packet(robotId, Write, Seq(Ax12.GoalPosition, 0xbc, 0x02)))
        readStatus(in, 6).error shouldBe 0
        eventually(timeout(10.seconds)) {
          out.write(packet(robotId, Read, Seq(Ax12.PresentPosition, 2)))
          val s = readStatus(in, 8)
          (s.params(0) | (s.params(1) << 8)) shouldBe 700
        }
        // A servo that does not answer: nothing comes back, and the next request is still answered.
        out.write(packet(42, Ping, Nil) ++ packet(3, Ping, Nil))
        readStatus(in, 6).id shouldBe 3

        // A second tool is refused while the first holds the bridge.
        val second = connectTo(base + robotId)
        Try(second.getInputStream.read()).getOrElse(-1) shouldBe -1
        second.close()

        client.close()
        leases.fishForMessage(10.seconds) {
          case BusBridgeClient(`robotId`, false) => FishingOutcomes.complete
          case _                                 => FishingOutcomes.continueAndIgnore
        }

        // A busBridge frame as a plain datagram is dropped by the robot, and counted.
        val plain =
          BusBridgeFrame.encode(robotId, BusBridge(1, request = Some(ByteString.copyFrom(packet(1, Ping, Nil)))))
        val udp = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
        udp.send(ByteBuffer.wrap(plain.get), address)
        eventually(timeout(10.seconds)) { f.view(robot).stats.busBridgeDropped shouldBe 1L }
        udp.close()
      } finally {
        testKit.stop(bridge)
        f.stop()
      }
    }

    "let nothing a stranger sends reach the tool or the bus: forged replies, another robot's id, replays, requests" in {
      val f = new GatewayFixture(testKit, BusBridgeSpec.Patient)
      val base = freeBase()
      val bridge = spawn(BusBridgeServer(f.gateway, BusBridgeSettings(enabled = true, basePort = base), None))
      // The stranger is another host on the field: another loopback address, any port.
      val stranger = DatagramChannel.open().bind(new InetSocketAddress(TestLoopback.address(0), 0))
      try {
        val (_, address) = streamRobot(f)
        f.awaitEvent(10.seconds) { case RobotOnline(`robotId`, _) => () }
        val client = answering(base + robotId)
        val out = client.getOutputStream
        val in = client.getInputStream
        out.write(packet(robotId, Read, Seq(Ax12.PresentPosition, 2)))
        val before = readStatus(in, 8)
        // A forged reply for the request the tool may be waiting on: as a plain frame, inside a forged stream segment,
        // and naming another robot; then a request to write a goal position sent straight to the robot.
        val forgedReply = BusBridge(0, reply = Some(ByteString.copyFrom(packet(robotId, 0, Seq(0x37, 0x01)))),
          result = Some(naogateway.proto.BusResult.BUS_OK))
        val frames = Seq(
          BusBridgeFrame.encode(robotId, forgedReply).get,
          Array[Byte](0, 20) ++ BusBridgeFrame.encode(robotId, forgedReply.withSequence(1)).get,
          BusBridgeFrame.encode(robotId + 1, forgedReply.withSequence(2)).get
        )
        (0 until 3).foreach(_ => frames.foreach(b => stranger.send(ByteBuffer.wrap(b), f.addresses.robots)))
        val goal = packet(robotId, Write, Seq(Ax12.GoalPosition, 0x37, 0x01))
        val request = BusBridgeFrame.encode(robotId, BusBridge(7, request = Some(ByteString.copyFrom(goal)))).get
        Seq(request, Array[Byte](0, 20) ++ request).foreach(b => stranger.send(ByteBuffer.wrap(b), address))
        Thread.sleep(1000)
        // The tool got nothing it did not ask for, and its next request is answered as before: the bus unchanged.
        in.available() shouldBe 0
        out.write(packet(robotId, Read, Seq(Ax12.PresentPosition, 2)))
        readStatus(in, 8) shouldBe before
        in.available() shouldBe 0
        client.close()
      } finally {
        stranger.close()
        testKit.stop(bridge)
        f.stop()
      }
    }

    "be closed while the competition gate is closed, and close its client when the game starts" in {
      val f = new GatewayFixture(
        testKit,
        BusBridgeSpec.Patient +
          "\ncompetition.enabled = on\ngame-controller.trusted-sources = [\"127.0.0.1\"]\n" +
          "game-controller.gate-open-after = 1s"
      )
      val base = freeBase()
      val bridge = spawn(BusBridgeServer(f.gateway, BusBridgeSettings(enabled = true, basePort = base), None))
      val gc = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      try {
        streamRobot(f)
        f.awaitEvent(10.seconds) { case RobotOnline(`robotId`, _) => () }
        // Closed: nothing listens.
        Thread.sleep(1000)
        Try(new Socket("127.0.0.1", base + robotId)).isFailure shouldBe true
        val next = f.openGate(gc)
        val client = answering(base + robotId)
        // PLAYING: the gate closes, and with it the bridge's client.
        val playing = GameControllerCodec.decodeControl(GameControllerVectors.bytes("v20-playing.bin")) match {
          case Right(d: Hsl20ControlData) => d.copy(packetNumber = next & 0xff)
          case other                      => fail(s"v20-playing.bin: $other")
        }
        gc.send(ByteBuffer.wrap(GameControllerCodec.encodeControl(playing).toOption.get),
          f.addresses.gameController.get)
        val closed =
          Try(client.getInputStream.read()).fold({ case _: SocketTimeoutException => 0; case _ => -1 }, identity)
        closed shouldBe -1
        client.close()
        // The listener's unbind follows the client's close (both asynchronous): soon nothing listens.
        val deadline = 5.seconds.fromNow
        def refused() = Try(new Socket("127.0.0.1", base + robotId)).fold(_ => true, s => { s.close(); false })
        while (!refused() && deadline.hasTimeLeft()) Thread.sleep(50)
        refused() shouldBe true
      } finally {
        gc.close()
        testKit.stop(bridge)
        f.stop()
      }
    }
  }
}

/** The fixture's settings for a loaded machine: a robot is given up only after 2 s of silence, not 0.85 s. */
object BusBridgeSpec {
  val Patient: String = "heartbeat.quiet-after = 1500ms\nheartbeat.probe-timeout = 500ms"
}
