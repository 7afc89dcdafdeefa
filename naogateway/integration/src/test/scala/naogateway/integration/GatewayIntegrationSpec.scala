package naogateway.integration

import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.ActorRef
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.{GatewayAccess, RobotAccess}
import naogateway.api.{
  CallResult,
  GameSource,
  GameStateUpdated,
  GatewayEvent,
  LinkQuality,
  LinkStats,
  RobotFailure,
  RobotLinks,
  RobotOffline,
  RobotOnline,
  RobotRestarted,
  RobotSnapshot,
  TrafficStats,
  VisionFrame
}
import naogateway.gateway.{Rejection, RejectionLedger}
import naogateway.gateway.robot.{Outbox, RobotEffects, RobotTestHooks}
import naogateway.sim.{FirmwareSettings, SimulatedRobot, ZeroMqSimulatedRobot}
import naogateway.testkit.{GameControllerCodecSupport, TestLoopback}
import naogateway.sim.network.{Impairment, LossyNetwork}
import naogateway.wire.{MessageContents, RpcCall, RpcValue}
import naogateway.wire.gamecontroller._

class GatewayIntegrationSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  private def call(c: RobotEffects.Connected, name: String, params: RpcValue*): CallResult = {
    val probe = createTestProbe[CallResult]()
    val (module, method) = name.span(_ != '.')
    c.response ! RobotAccess.Call(RpcCall(module, method.drop(1), params.toVector), probe.ref)
    probe.receiveMessage(10.seconds)
  }

  /** Runs `test` against a fresh fixture and stops its gateway and robots afterwards, whatever the outcome. */
  private def withGateway[A](overrides: String = "")(test: GatewayFixture => A): A = {
    val f = new GatewayFixture(testKit, overrides)
    try test(f)
    finally f.stop()
  }

  private def sendGameState(gc: DatagramChannel, f: GatewayFixture, state: GameState): Unit = {
    val data = GameControllerCodecSupport.playing(teamNumber = 1).copy(gameState = state)
    gc.send(ByteBuffer.wrap(GameControllerCodec.encodeControl(data).toOption.get), f.addresses.gameController.get)
    ()
  }

  "The gateway" must {
    "free its robot port when it stops, however often it is started, with no reader thread of its own" in {
      def readers = Thread.getAllStackTraces.keySet.toArray(Array.empty[Thread])
        .count(t => t.isAlive && t.getName == s"${system.name}-robot-port")
      val before = readers
      (1 to 5).foreach { _ =>
        val f = new GatewayFixture(testKit)
        // The default robot dispatcher is a port loop: its thread reads the port, no reader thread is started.
        readers shouldBe before
        f.stop()
        readers shouldBe before
        // Closed with the gateway, not left to the garbage collector: the port can be bound again at once.
        DatagramChannel.open().bind(f.addresses.robots).close()
      }
    }
    "read its robot port on the robot dispatcher's one thread, which waits in the port's selector when idle" in
      withGateway() { f =>
        f.robot(15)
        f.awaitEvent(10.seconds) { case RobotOnline(15, _) => () }
        def robotThreads = Thread.getAllStackTraces.asScala.filter { case (t, _) =>
          t.isAlive && t.getName.startsWith(s"${system.name}-naogateway.dispatcher")
        }
        robotThreads.size shouldBe 1
        // Between keep-alives the thread that runs the robot actors waits for the robot port, not in a task queue.
        eventually(timeout(10.seconds)) {
          val (_, stack) = robotThreads.head
          stack.exists(e => e.getClassName.endsWith("SelectorImpl") && e.getMethodName == "select") shouldBe true
        }
      }
    "take game state only from its trusted GameController: a forged PLAYING from elsewhere changes nothing" in
      withGateway("competition.enabled = on\ngame-controller.trusted-sources = [\"127.0.0.1\"]") { f =>
        val stranger = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.2", 0))
        val gc = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
        try {
          (1 to 5).foreach(_ => sendGameState(stranger, f, GameState.Playing))
          val source = createTestProbe[GameSource]()
          source.awaitAssert({
              f.gateway ! GatewayAccess.GetGameSource(source.ref)
              source.receiveMessage().untrusted shouldBe 5L
            }, 10.seconds)
          val game = createTestProbe[Option[GameControlData]]()
          f.gateway ! GatewayAccess.GetGameState(game.ref)
          game.receiveMessage() shouldBe None
          val traffic = createTestProbe[TrafficStats]()
          f.gateway ! GatewayAccess.GetTraffic(traffic.ref)
          // Competition mode starts closed, and a stranger's packets neither close nor open it.
          val closed = traffic.receiveMessage()
          closed.gateOpen shouldBe false
          closed.gateReason shouldBe Some(
            "no packet from the trusted GameController yet (competition mode starts closed)")
          // The trusted GameController's packet counts, and the view learns where game state comes from.
          sendGameState(gc, f, GameState.Playing)
          f.awaitEvent(10.seconds) { case GameStateUpdated(d) if d.gameState == GameState.Playing => () }
          f.gateway ! GatewayAccess.GetGameSource(source.ref)
          val seen = source.receiveMessage()
          seen.lastFrom.map(_.getAddress.getHostAddress) shouldBe Some("127.0.0.1")
          seen.describe should include("trusted: 127.0.0.1/32")
          seen.describe should include("5 packet(s) from elsewhere ignored")
        } finally { stranger.close(); gc.close() }
      }
    "refuse to start competition mode without a trusted GameController source, or trusting too wide a range" in {
      val e = intercept[IllegalArgumentException](new GatewayFixture(testKit, "competition.enabled = on"))
      e.getMessage should include("trusted-sources")
      Seq("0.0.0.0/0", "127.0.0.0/8", "10.0.0.0/31").foreach { range =>
        val wide = intercept[IllegalArgumentException](new GatewayFixture(testKit,
            s"competition.enabled = on\ngame-controller.trusted-sources = [\"$range\"]"))
        wide.getMessage should include("max-trusted-range")
      }
      val zero = intercept[IllegalArgumentException](new GatewayFixture(testKit,
          "competition.enabled = on\ngame-controller.trusted-sources = [\"0.0.0.0/0\"]\n" +
            "game-controller.max-trusted-range = 1"))
      zero.getMessage should include("max-trusted-range")
    }
    "send requests and option commands to the robot's receive port (its IP, 3838), nothing to where it sends from" in
      withGateway() { f =>
        val (robot, receivesAt) = f.robot(13)
        val online = f.awaitEvent(10.seconds) { case RobotOnline(13, address) => address }
        // Known at its IP and receive port, although every datagram it sent came from another port.
        online shouldBe receivesAt
        online.getPort shouldBe 3838
        f.view(robot).sendingFrom.getPort should not be 3838
        val connected = f.connect(13)
        call(connected, "system.ping").result.isRight shouldBe true
        connected.registrations ! RobotAccess.RegisterVision(createTestProbe[VisionFrame]().ref, grid = false)
        eventually(timeout(10.seconds)) { f.view(robot).debugEnabled should contain("havimo.regions") }
        val view = f.view(robot)
        view.stats.received should be >= 3L
        // Had the gateway answered to the keep-alives' source port, the robot would have ignored (and counted) it all.
        view.stats.ignoredAtSendingSocket shouldBe 0L
      }
    "keep a robot that starts sending from another port online, known once, and reached at its receive port" in
      withGateway() { f =>
        val (robot, receivesAt) = f.robot(14)
        f.awaitEvent(10.seconds) { case RobotOnline(14, _) => () }
        val connected = f.connect(14)
        call(connected, "system.ping").result.isRight shouldBe true
        def heard(): Long = {
          val stats = createTestProbe[LinkStats]()
          f.robotAccess(14) ! RobotAccess.GetLinkStats(stats.ref)
          stats.receiveMessage(5.seconds).datagramsIn
        }
        // The module reconnects: its client connection, and so the source port of everything it sends, is new.
        val before = f.view(robot).sendingFrom
        val moved = createTestProbe[InetSocketAddress]()
        robot ! SimulatedRobot.Reconnect(moved.ref)
        val now = moved.receiveMessage(10.seconds)
        now should not be before
        // Fifteen keep-alives from the new port reach the robot actor: three seconds, several times the time after
        // which a silent robot goes offline (quiet-after + 3 probes).
        val counted = heard()
        eventually(timeout(20.seconds), interval(100.millis)) { heard() should be >= counted + 15 }
        call(connected, "system.ping").result.isRight shouldBe true
        // Every event so far (status updates come five times a second, so a 100 ms pause means none is waiting).
        val seen = Iterator.continually(scala.util.Try(f.events.receiveMessage(100.millis)).toOption).takeWhile(
          _.isDefined).flatten.toVector
        seen.collect { case e: RobotOffline => e } shouldBe empty
        val robots = createTestProbe[Vector[RobotSnapshot]]()
        f.gateway ! GatewayAccess.GetRobots(robots.ref)
        robots.receiveMessage(10.seconds).map(s => (s.robotId, s.online, s.address)) shouldBe Vector((14, true,
            receivesAt))
        f.stats().rejected.get(Rejection.RobotIdMismatch.name) shouldBe None
        f.view(robot).stats.ignoredAtSendingSocket shouldBe 0L
      }
    "discover several robots from their keep-alives and answer calls to each" in withGateway() { f =>
      val robots = (1 to 3).map(id => id -> f.robot(id))
      val online = (1 to 3).map(_ => f.awaitEvent(10.seconds) { case RobotOnline(id, address) => id -> address }).toMap
      online.keySet shouldBe Set(1, 2, 3)
      robots.foreach { case (id, (_, address)) => online(id) shouldBe address }
      (1 to 3).foreach { id =>
        call(f.connect(id), "system.ping").result.isRight shouldBe true
        call(f.connect(id), "motion.getPosture").result shouldBe Right(Some(RpcValue.Text("sit")))
      }
      val robotsProbe = createTestProbe[Vector[RobotSnapshot]]()
      f.gateway ! GatewayAccess.GetRobots(robotsProbe.ref)
      robotsProbe.receiveMessage().map(s => (s.robotId, s.online, s.quality)) shouldBe
        Vector((1, true, LinkQuality.Good), (2, true, LinkQuality.Good), (3, true, LinkQuality.Good))
      // The read-only view: the same robots' link figures, through a ref that can ask but not send.
      val view: ActorRef[GatewayAccess.Query] = f.gateway
      val links = createTestProbe[RobotLinks]()
      view ! GatewayAccess.GetLinkStats(links.ref)
      val figures = links.receiveMessage().links
      figures.map(_.robotId) shouldBe Vector(1, 2, 3)
      // Each answered at least its two calls, so each received datagrams and sent some.
      all(figures.map(_.datagramsIn)) should be > 0L
      all(figures.map(_.datagramsOut)) should be >= 2L
    }

    "take a partitioned robot offline within its three chances and back online when the partition heals" in withGateway() {
      f =>
        val network = LossyNetwork.start(seed = 3)
        try {
          val proxy = network.addProxy(f.addresses.robots, TestLoopback.address())
          f.robot(7, to = proxy.clientSide)
          f.awaitEvent(10.seconds) { case RobotOnline(7, _) => () }
          val connected = f.connect(7)
          network.partition(proxy, on = true)
          // The three chances themselves, in manual time, are HeartBeatActorSpec's; here the reason names them.
          f.awaitEvent(10.seconds) { case RobotOffline(7, reason) => reason should include("3 unanswered probes") }
          call(connected, "system.ping").result shouldBe Left(RobotFailure.RobotOffline(7))
          network.partition(proxy, on = false)
          f.awaitEvent(10.seconds) { case RobotOnline(7, _) => () }
          call(connected, "system.ping").result.isRight shouldBe true
        } finally network.stop()
    }

    "re-sync a power-cycled robot by itself: same address, new session, debug options enabled again" in withGateway() {
      f =>
        val (robot, _) = f.robot(4)
        f.awaitEvent(10.seconds) { case RobotOnline(4, _) => () }
        val connected = f.connect(4)
        connected.registrations ! RobotAccess.RegisterVision(createTestProbe[VisionFrame]().ref, grid = false)
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

    "answer every call exactly once at 20 % loss each way, and keep fire-and-forget commands in order" in withGateway() {
      f =>
        val network = LossyNetwork.start(seed = 11)
        try {
          val lossy = Impairment(loss = 0.2)
          val proxy = network.addProxy(f.addresses.robots, TestLoopback.address(), uplink = lossy, downlink = lossy)
          val (robot, _) = f.robot(5, to = proxy.clientSide)
          f.awaitEvent(10.seconds) { case RobotOnline(5, _) => () }
          val connected = f.connect(5)
          val answers = createTestProbe[CallResult]()
          (1 to 40).foreach(_ =>
            connected.response ! RobotAccess.Call(RpcCall("system", "ping", Vector.empty), answers.ref))
          val results = answers.receiveMessages(40, 60.seconds)
          answers.expectNoMessage(3.seconds)
          results.count(_.result.isRight) should be > 20
          // In-order speech: only texts that arrived are recorded, and they arrive in the order sent.
          val said = createTestProbe[CallResult]()
          (1 to 10).foreach(i =>
            RobotTestHooks.sendOnce(connected.response, RpcCall("speech", "say", Vector(RpcValue.Text(s"$i"))),
              Some(said.ref)))
          said.receiveMessages(10, 60.seconds)
          val texts = f.view(robot).said.map(_.toInt)
          texts shouldBe texts.sorted
          texts.distinct shouldBe texts
        } finally network.stop()
    }

    "send nothing to a robot while the game runs in competition mode, and fail calls at once naming the rule" in
      withGateway("competition.enabled = on\ngame-controller.trusted-sources = [\"127.0.0.0/8\"]\n" +
        "game-controller.max-trusted-range = 8\ngame-controller.gate-open-after = 1s") { f =>
        val (robot, _) = f.robot(6)
        f.awaitEvent(10.seconds) { case RobotOnline(6, _) => () }
        val connected = f.connect(6)
        val gc = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
        try {
          val next = f.openGate(gc)
          eventually(timeout(20.seconds)) { call(connected, "system.ping").result.isRight shouldBe true }
          sendGameState(gc, f, GameState.Playing)
          f.awaitEvent(10.seconds) { case GameStateUpdated(d) if d.gameState == GameState.Playing => () }
          // The gateway told the outbox before it published kick-off, so this question reaches the outbox after the
          // gate closed: the count is final, and robot 6 is the only one the outbox ever sent to.
          val atKickOff = f.traffic()
          atKickOff.gameRunning shouldBe true
          // Datagrams sent just before kick-off may still be on their way; once the robot has counted every one of
          // them, nothing is in flight any more.
          eventually(timeout(10.seconds)) { f.view(robot).stats.received shouldBe atKickOff.datagramsOut }
          (1 to 5).foreach { _ =>
            call(connected, "system.ping").result shouldBe Left(RobotFailure.RuleGate(Outbox.NoSendingWhileGameRuns))
          }
          /* Two seconds of heartbeat probing, status traffic and calls: nothing may leave the outbox or reach the
           * robot. */
          Thread.sleep(2000)
          val during = f.traffic()
          during.datagramsOut shouldBe atKickOff.datagramsOut
          during.refusedByRule should be >= atKickOff.refusedByRule + 5
          f.view(robot).stats.received shouldBe atKickOff.datagramsOut
          sendGameState(gc, f, GameState.Finished)
          f.awaitEvent(10.seconds) { case GameStateUpdated(d) if d.gameState == GameState.Finished => () }
          // FINISHED opens the gate only after gate-open-after of such packets (docs/protocol.md 10.7).
          f.traffic().gateOpen shouldBe false
          f.openGate(gc, next, GameState.Finished)
          eventually(timeout(20.seconds)) { call(connected, "system.ping").result.isRight shouldBe true }
        } finally gc.close()
      }

    "close a ZeroMQ robot's gate before any subscriber hears of kick-off" in {
      val zeroMqRobot = new ZeroMqSimulatedRobot(FirmwareSettings(robotId = 25), "tcp://127.0.0.1:*")
      zeroMqRobot.start()
      try {
        val endpoint = zeroMqRobot.boundEndpoint.get
        withGateway(s"""competition.enabled = on
          |game-controller.trusted-sources = ["127.0.0.0/8"]
          |game-controller.max-trusted-range = 8
          |game-controller.gate-open-after = 1s
            |zeromq.robots = [{ id = 25, endpoint = "$endpoint" }]""".stripMargin) { f =>
          // Competition mode starts closed, and a ZeroMQ robot comes online only through the gate (its status polls):
          // the GameController that opens it is the one that runs the game (a second one would be ignored).
          val gc = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
          val next =
            try f.openGate(gc)
            catch { case e: Throwable => gc.close(); throw e }
          f.awaitEvent(15.seconds) { case RobotOnline(25, _) => () }
          val connected = f.connect(25)
          eventually(timeout(20.seconds)) { call(connected, "system.ping").result.isRight shouldBe true }
          // A subscriber that calls the robot in the very message that tells it of kick-off.
          val results = createTestProbe[CallResult]()
          val eager = spawn(Behaviors.receiveMessage[GatewayEvent] {
            case GameStateUpdated(d) if d.gameState == GameState.Playing =>
              connected.response ! RobotAccess.Call(RpcCall("system", "ping", Vector.empty), results.ref)
              Behaviors.stopped
            case _ => Behaviors.same
          })
          // Subscribed before the packet is sent, so the gateway knows the subscriber when kick-off arrives.
          f.gateway ! GatewayAccess.Subscribe(eager)
          try {
            sendGameState(gc, f, GameState.Playing)
            results.receiveMessage(10.seconds).result shouldBe Left(
              RobotFailure.RuleGate(Outbox.NoSendingWhileGameRuns))
            sendGameState(gc, f, GameState.Finished)
            f.awaitEvent(10.seconds) { case GameStateUpdated(d) if d.gameState == GameState.Finished => () }
            f.openGate(gc, next, GameState.Finished)
            // Without status polls during the game the robot may have been taken offline; a call brings it back.
            eventually(timeout(20.seconds)) { call(connected, "system.ping").result.isRight shouldBe true }
          } finally gc.close()
        }
      } finally zeroMqRobot.stop()
    }

    "relay every robot datagram byte-identical to FU-Remote and reject spoofed robot ids" in {
      val fuRemote = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      fuRemote.configureBlocking(true)
      try {
        val port = fuRemote.getLocalAddress.asInstanceOf[InetSocketAddress].getPort
        withGateway(s"""fu-remote-relay { enabled = on, address = "127.0.0.1", port = $port }""") { f =>
          f.robot(8)
          f.awaitEvent(10.seconds) { case RobotOnline(8, _) => () }
          val spoofer = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
          try {
            val keepAlive = MessageContents
              .encodeFrame(MessageContents(8, status = Some(naogateway.proto.Status(teamID = Some(1)))))
              .toOption
              .get
            spoofer.send(ByteBuffer.wrap(keepAlive), f.addresses.robots)
            // The relay forwards what it receives, spoofed or not, unchanged; the robot's own traffic comes in between.
            val deadline = 10.seconds.fromNow
            var copies = Vector.empty[Array[Byte]]
            while (!copies.exists(_.sameElements(keepAlive)) && deadline.hasTimeLeft()) {
              val socket = fuRemote.socket()
              socket.setSoTimeout(math.max(1L, deadline.timeLeft.toMillis).toInt)
              val packet = new java.net.DatagramPacket(new Array[Byte](2048), 2048)
              try {
                socket.receive(packet)
                copies :+= java.util.Arrays.copyOf(packet.getData, packet.getLength)
              } catch { case _: java.net.SocketTimeoutException => () }
            }
            copies.exists(_.sameElements(keepAlive)) shouldBe true
            copies.forall(c => MessageContents.decodeFrame(c).isRight) shouldBe true
            eventually(timeout(5.seconds)) {
              f.stats().rejected.get(Rejection.RobotIdMismatch.name).exists(_ >= 1L) shouldBe true
            }
          } finally spoofer.close()
        }
      } finally fuRemote.close()
    }

    "keep every robot's session working while arbitrary bytes are sprayed at its port" in withGateway() { f =>
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
        // Counted by kind, a closed set, whatever the bytes said; and by source, bounded.
        val stats = f.stats()
        stats.rejected.keySet.subsetOf(Rejection.all.map(_.name).toSet) shouldBe true
        stats.rejectedBySource.size should be <= RejectionLedger.SourceAddresses + 1
        // No session was disturbed: nobody went offline or looked restarted.
        val seen = f.events.receiveMessages(10, 5.seconds)
        seen.collect { case e @ (_: RobotOffline | _: RobotRestarted) => e } shouldBe empty
      } finally sprayer.close()
    }
  }
}
