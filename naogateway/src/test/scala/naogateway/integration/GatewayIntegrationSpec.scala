package naogateway.integration

import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway._
import naogateway.sim.SimulatedRobot
import naogateway.sim.network.{Impairment, LossyNetwork}
import naogateway.wire.{MessageContents, RpcCall, RpcValue}
import naogateway.wire.gamecontroller._

class GatewayIntegrationSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  private def call(c: RobotActor.Connected, name: String, params: RpcValue*): CallResult = {
    val probe = createTestProbe[CallResult]()
    val (module, method) = name.span(_ != '.')
    c.response ! ResponseActor.Call(RpcCall(module, method.drop(1), params.toVector), probe.ref)
    probe.receiveMessage(10.seconds)
  }

  "The gateway" must {
    "discover several robots from their keep-alives and answer calls to each" in {
      val f = new GatewayFixture(testKit)
      val robots = (1 to 3).map(id => id -> f.robot(id))
      val online = (1 to 3).map(_ => f.awaitEvent(10.seconds) { case RobotOnline(id, address) => id -> address }).toMap
      online.keySet shouldBe Set(1, 2, 3)
      robots.foreach { case (id, (_, address)) => online(id) shouldBe address }
      (1 to 3).foreach { id =>
        call(f.connect(id), "system.ping").result.isRight shouldBe true
        call(f.connect(id), "motion.getPosture").result shouldBe Right(Some(RpcValue.Text("sit")))
      }
      val robotsProbe = createTestProbe[Vector[RobotSnapshot]]()
      f.gateway ! Gateway.GetRobots(robotsProbe.ref)
      robotsProbe.receiveMessage().map(s => (s.robotId, s.online, s.quality)) shouldBe
        Vector((1, true, LinkQuality.Good), (2, true, LinkQuality.Good), (3, true, LinkQuality.Good))
    }

    "take a partitioned robot offline within its three chances and back online when the partition heals" in {
      val f = new GatewayFixture(testKit)
      val network = LossyNetwork.start(seed = 3)
      try {
        val proxy = network.addProxy(f.addresses.robots)
        f.robot(7, to = proxy.clientSide)
        f.awaitEvent(10.seconds) { case RobotOnline(7, _) => () }
        val connected = f.connect(7)
        network.partition(proxy, on = true)
        val cut = System.nanoTime()
        f.awaitEvent(10.seconds) { case RobotOffline(7, reason) => reason should include("3 unanswered probes") }
        val detection = (System.nanoTime() - cut).nanos
        // Silence (400 ms) plus three probe timeouts (3 x 150 ms), with room for a loaded machine.
        detection should be >= 800.millis
        call(connected, "system.ping").result shouldBe Left(CallError.RobotOffline(7))
        network.partition(proxy, on = false)
        f.awaitEvent(10.seconds) { case RobotOnline(7, _) => () }
        call(connected, "system.ping").result.isRight shouldBe true
      } finally network.stop()
    }

    "re-sync a power-cycled robot by itself: same address, new session, debug options enabled again" in {
      val f = new GatewayFixture(testKit)
      val (robot, _) = f.robot(4)
      f.awaitEvent(10.seconds) { case RobotOnline(4, _) => () }
      val connected = f.connect(4)
      connected.vision ! VisionActor.Register(createTestProbe[VisionFrame]().ref, grid = false)
      eventually(timeout(5.seconds)) { f.view(robot).debugEnabled should contain("havimo.regions") }
      robot ! SimulatedRobot.PowerCycle(1.second)
      val restarted = f.awaitEvent(20.seconds) { case r: RobotRestarted if r.robotId == 4 => r }
      restarted.bootId shouldBe Some(2)
      restarted.resynced should contain("havimo.regions")
      eventually(timeout(5.seconds)) {
        val view = f.view(robot)
        view.bootId shouldBe 2
        view.debugEnabled should contain("havimo.regions")
      }
    }

    "answer every call exactly once at 20 % loss each way, and keep fire-and-forget commands in order" in {
      val f = new GatewayFixture(testKit)
      val network = LossyNetwork.start(seed = 11)
      try {
        val lossy = Impairment(loss = 0.2)
        val proxy = network.addProxy(f.addresses.robots, uplink = lossy, downlink = lossy)
        val (robot, _) = f.robot(5, to = proxy.clientSide)
        f.awaitEvent(10.seconds) { case RobotOnline(5, _) => () }
        val connected = f.connect(5)
        val answers = createTestProbe[CallResult]()
        (1 to 40).foreach(_ => connected.response ! ResponseActor.Call(RpcCall("system", "ping", Vector.empty), answers.ref))
        val results = answers.receiveMessages(40, 60.seconds)
        answers.expectNoMessage(3.seconds)
        results.count(_.result.isRight) should be > 20
        // In-order speech: only texts that arrived are recorded, and they arrive in the order sent.
        val said = createTestProbe[CallResult]()
        (1 to 10).foreach(i =>
          connected.noResponse ! NoResponseActor.Send(RpcCall("speech", "say", Vector(RpcValue.Text(s"$i"))), Some(said.ref)))
        said.receiveMessages(10, 60.seconds)
        val texts = f.view(robot).said.map(_.toInt)
        texts shouldBe texts.sorted
        texts.distinct shouldBe texts
      } finally network.stop()
    }

    "send nothing to a robot while the game runs in competition mode, and fail calls at once naming the rule" in {
      val f = new GatewayFixture(testKit, "competition.enabled = on")
      val (robot, _) = f.robot(6)
      f.awaitEvent(10.seconds) { case RobotOnline(6, _) => () }
      val connected = f.connect(6)
      call(connected, "system.ping").result.isRight shouldBe true
      val gc = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      try {
        val packet = GameControllerCodec.encodeControl(GameControllerCodecSupport.playing(teamNumber = 1)).toOption.get
        gc.send(ByteBuffer.wrap(packet), f.addresses.gameController.get)
        f.awaitEvent(10.seconds) { case GameStateUpdated(d) if d.gameState == GameState.Playing => () }
        val before = f.view(robot).counters.received
        (1 to 5).foreach { _ =>
          call(connected, "system.ping").result shouldBe Left(CallError.RuleGate(Outbox.NoSendingWhileGameRuns))
        }
        // Two seconds of heartbeat probing, status traffic and calls: nothing may reach the robot.
        Thread.sleep(2000)
        f.view(robot).counters.received shouldBe before
        val finished = GameControllerCodecSupport.playing(teamNumber = 1).copy(gameState = GameState.Finished)
        gc.send(ByteBuffer.wrap(GameControllerCodec.encodeControl(finished).toOption.get), f.addresses.gameController.get)
        f.awaitEvent(10.seconds) { case GameStateUpdated(d) if d.gameState == GameState.Finished => () }
        call(connected, "system.ping").result.isRight shouldBe true
      } finally gc.close()
    }

    "relay every robot datagram byte-identical to FU-Remote and reject spoofed robot ids" in {
      val fuRemote = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      fuRemote.configureBlocking(true)
      fuRemote.socket().setSoTimeout(5000)
      try {
        val port = fuRemote.getLocalAddress.asInstanceOf[InetSocketAddress].getPort
        val f = new GatewayFixture(testKit, s"""fu-remote-relay { enabled = on, address = "127.0.0.1", port = $port }""")
        f.robot(8)
        f.awaitEvent(10.seconds) { case RobotOnline(8, _) => () }
        val spoofer = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
        try {
          val keepAlive = MessageContents
            .encodeFrame(MessageContents(8, status = Some(naogateway.proto.Status(teamID = Some(1)))))
            .toOption
            .get
          spoofer.send(ByteBuffer.wrap(keepAlive), f.addresses.robots)
          // The relay forwards what it receives, spoofed or not, unchanged.
          val copies = Iterator
            .continually {
              val buffer = ByteBuffer.allocate(2048)
              val socket = fuRemote.socket()
              val packet = new java.net.DatagramPacket(buffer.array(), buffer.capacity())
              socket.receive(packet)
              java.util.Arrays.copyOf(packet.getData, packet.getLength)
            }
            .take(15)
            .toVector
          copies.exists(_.sameElements(keepAlive)) shouldBe true
          copies.forall(c => MessageContents.decodeFrame(c).isRight) shouldBe true
          eventually(timeout(5.seconds)) {
            f.stats().rejected.keys.exists(_.contains("robot id 8 claimed from another address")) shouldBe true
          }
        } finally spoofer.close()
      } finally fuRemote.close()
    }

    "keep every robot's session working while arbitrary bytes are sprayed at its port" in {
      val f = new GatewayFixture(testKit)
      (1 to 2).foreach(id => f.robot(id))
      (1 to 2).foreach(_ => f.awaitEvent(10.seconds) { case RobotOnline(_, _) => () })
      val sprayer = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      try {
        val random = new scala.util.Random(5)
        (1 to 3000).foreach { i =>
          val size = random.nextInt(1500) + 1
          val bytes = Array.fill[Byte](size)(random.nextInt(256).toByte)
          // Mix in datagrams that look like frames, GameController packets and stream segments.
          i % 4 match {
            case 0 => bytes(0) = 0; if (size > 1) bytes(1) = 42
            case 1 => if (size > 3) { bytes(0) = 'R'; bytes(1) = 'G'; bytes(2) = 'm'; bytes(3) = 'e' }
            case 2 => bytes(0) = (random.nextInt(42)).toByte; if (size > 1) bytes(1) = random.nextInt(42).toByte
            case _ => ()
          }
          sprayer.send(ByteBuffer.wrap(bytes), f.addresses.robots)
        }
        (1 to 2).foreach(id => call(f.connect(id), "system.ping").result.isRight shouldBe true)
        eventually(timeout(10.seconds)) { f.stats().rejected.values.sum should be >= 1000L }
        // No session was disturbed: nobody went offline or looked restarted.
        val seen = f.events.receiveMessages(10, 5.seconds)
        seen.collect { case e @ (_: RobotOffline | _: RobotRestarted) => e } shouldBe empty
      } finally sprayer.close()
    }
  }
}
