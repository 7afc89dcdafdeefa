package naogateway.sim

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.Done
import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.actor.typed.ActorRef
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.proto.{DebuggingCommands, DebuggingOptionNames}
import naogateway.testkit.TestLoopback
import naogateway.wire.{MessageContents, Posture, RpcValue, WireLimits}

class SimulatedRobotSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {
  import RpcValue._

  private def withGateway[A](test: TestGateway => A): A = {
    val gateway = new TestGateway
    try test(gateway)
    finally gateway.close()
  }

  private def settings(gateway: TestGateway, firmware: FirmwareSettings): SimulatedRobotSettings =
    SimulatedRobotSettings(firmware, gateway.address, bindAddress = new InetSocketAddress(TestLoopback.address(), 0))

  private def state(robot: ActorRef[SimulatedRobot.Command]): RobotView = {
    val probe = createTestProbe[RobotView]()
    robot ! SimulatedRobot.GetState(probe.ref)
    probe.receiveMessage(5.seconds)
  }

  private def start(settings: SimulatedRobotSettings): (ActorRef[SimulatedRobot.Command], InetSocketAddress) = {
    val robot = spawn(SimulatedRobot(settings))
    (robot, state(robot).address)
  }

  private def stop(robot: ActorRef[SimulatedRobot.Command]): Unit = {
    val probe = createTestProbe[Done]()
    robot ! SimulatedRobot.Stop(probe.ref)
    probe.expectMessage(5.seconds, Done)
  }

  private def result(gateway: TestGateway, robot: InetSocketAddress, module: String, method: String, params: RpcValue*)
      : Either[String, Option[RpcValue]] = {
    val (reply, heard) = gateway.call(robot, module, method, params: _*).getOrElse(fail(s"no reply to $module.$method"))
    // From the robot's host, but from its sending socket: the receive socket never sends.
    heard.from.getAddress shouldBe robot.getAddress
    heard.from.getPort should not be robot.getPort
    reply.result
  }

  private def keepAlive(heard: Heard): Option[MessageContents] = heard.contents.filter(_.status.isDefined)

  private val ok = Right(Some(Flag(true)))

  "A simulated robot" should {
    "receive on its own address at 3838, send from another socket, and act on nothing sent to that one" in withGateway {
      gateway =>
        val (robot, address) = start(settings(gateway, FirmwareSettings(robotId = 12)))
        val sendingFrom = state(robot).sendingFrom
        address.getPort shouldBe 3838
        sendingFrom.getAddress shouldBe address.getAddress
        sendingFrom.getPort should not be 3838
        // A request to the port the robot's datagrams come from: the module's client connection passes it on to nobody.
        gateway.send(TestGateway.request("system", "ping", Vector.empty, 4711), sendingFrom)
        createTestProbe[Any]().awaitAssert(state(robot).stats.ignoredAtSendingSocket shouldBe 1, 10.seconds)
        state(robot).firmware.rpcCalls shouldBe 0
        // The same request at the receive port is answered, from the sending socket.
        val (reply, heard) = gateway.call(address, "system", "ping").getOrElse(fail("no reply at the receive port"))
        reply.result.isRight shouldBe true
        heard.from shouldBe sendingFrom
        // Reconnect: a new source port, the same receive port.
        val moved = createTestProbe[InetSocketAddress]()
        robot ! SimulatedRobot.Reconnect(moved.ref)
        val now = moved.receiveMessage(5.seconds)
        now should not be sendingFrom
        now.getAddress shouldBe address.getAddress
        gateway.drain()
        gateway.call(address, "system", "ping").map(_._2.from) shouldBe Some(now)
        state(robot).stats.ignoredAtSendingSocket shouldBe 1
        stop(robot)
    }

    "send keep-alives that decode into its Status and RobotHealth, and never a datagram over 1400 bytes" in withGateway {
      gateway =>
        val (robot, address) = start(settings(gateway, FirmwareSettings(robotId = 7, teamId = 12, role = "keeper")))
        // Every debug option on, so the robot's largest datagrams (HaViMo2 grid, camera image) are among those checked.
        val all = DebuggingOptionNames(RobotFirmware.OptionCatalogue.map(_._1))
        val enable = MessageContents(7, debuggingCommands = Some(DebuggingCommands(optionEnable = Some(all))))
        gateway.send(MessageContents.encodeFrame(enable).toOption.get, address)
        val heard = gateway.collectFor(2.seconds)
        stop(robot)

        heard.size should be > 20
        heard.foreach { h =>
          h.bytes.length should be <= WireLimits.MaxDatagramBytes
          h.from.getAddress shouldBe address.getAddress
        }
        heard.map(_.bytes.length).max should be > 700
        heard.flatMap(_.contents).exists(_.havimoGrid.isDefined) shouldBe true
        val keepAlives = heard.flatMap(keepAlive)
        keepAlives.size should be >= 3
        val first = keepAlives.head
        first.robotId shouldBe 7
        val status = first.status.get
        status.teamID shouldBe Some(12)
        status.activeRole shouldBe Some("keeper")
        status.activeAgent shouldBe Some("SimAgent")
        status.currentState shouldBe Some("sit")
        status.robotPosition.flatMap(_.x) shouldBe Some(-1000)
        val health = first.robotHealth.get
        health.batteryVoltage.get.toDouble shouldBe 12.4 +- 0.01
        health.posture shouldBe Some("sit")
        health.bootId shouldBe Some(1)
    }

    "answer the documented calls over loopback, and an unknown method with its error" in withGateway { gateway =>
      val (robot, address) = start(settings(gateway, FirmwareSettings(robotId = 2)))
      result(gateway, address, "system", "battery") match {
        case Right(Some(Number(volts))) => volts.toDouble shouldBe 12.4 +- 0.01
        case other                      => fail(s"battery: $other")
      }
      val firstPing = result(gateway, address, "system", "ping")
      val secondPing = result(gateway, address, "system", "ping")
      (firstPing, secondPing) match {
        case (Right(Some(UInt(a))), Right(Some(UInt(b)))) => b should be >= a
        case other                                        => fail(s"ping: $other")
      }
      result(gateway, address, "motion", "getPosture") shouldBe Right(Some(Text("sit")))
      result(gateway, address, "speech", "say", Text("hello")) shouldBe ok
      result(gateway, address, "motion", "head", Number(0.5f), Number(-0.2f)) shouldBe ok
      result(gateway, address, "heartbeat", "probe") shouldBe Left("unknown method: heartbeat.probe")

      val view = state(robot)
      view.said shouldBe Vector("hello")
      view.head._1 shouldBe 0.5 +- 1e-6
      view.head._2 shouldBe -0.2 +- 1e-6
      view.firmware.rpcCalls shouldBe 7
      view.module.map(_.readIntact) shouldBe Some(7L)
      stop(robot)
    }

    "stop walking by itself when the 500 ms walk lease is not refreshed" in withGateway { gateway =>
      val (robot, address) = start(settings(gateway, FirmwareSettings(robotId = 3, standUpTime = 300.millis)))
      result(gateway, address, "motion", "posture", Text("stand")) shouldBe Right(Some(Text("stand")))
      result(gateway, address, "motion", "walk", Number(0.2f), Number(0f), Number(0f)) shouldBe ok
      // Standing again 0.1 m further on: exactly 0.5 s at 0.2 m/s, the lease and not a step more.
      val stood = gateway.await(3.seconds) { heard =>
        keepAlive(heard).flatMap(_.status).filter(s =>
          s.currentState.contains("stand") && s.getRobotPosition.getX > -1000)
      }
      stood.flatMap(_.robotPosition).flatMap(_.x) shouldBe Some(-900)
      val view = state(robot)
      view.posture shouldBe Posture.Stand
      view.pose.x shouldBe -0.9 +- 1e-3
      stop(robot)
    }

    "fall silent for the boot delay when power-cycled, then come back as a new session" in withGateway { gateway =>
      val (robot, address) = start(settings(gateway, FirmwareSettings(robotId = 5)))
      // Up well beyond the 1 s boot delay, so the new session's uptime is clearly smaller.
      val uptimeBefore = gateway
        .await(8.seconds)(h => keepAlive(h).flatMap(_.robotHealth).flatMap(_.uptimeMs).filter(_ >= 2500))
        .getOrElse(fail("no keep-alive after 2.5 s of uptime"))

      val cutAt = System.nanoTime()
      robot ! SimulatedRobot.PowerCycle(1.second)
      val off = state(robot)
      off.online shouldBe false
      off.bootId shouldBe 2
      off.onlineAgainIn.exists(_ <= 1.second) shouldBe true
      // Sent to a silent robot: never answered, not even after it is back.
      gateway.send(TestGateway.request("system", "ping", Vector.empty, 4242), address)

      var answered = false
      def noteAnswer(heard: Heard): Unit =
        if (heard.contents.flatMap(_.rpcResponse).flatMap(_.callId).contains(4242)) answered = true

      // Until 0.9 s after the cut only datagrams sent before it may arrive (boot 1).
      val silent = gateway.collectFor(math.max(0L, cutAt + 900.millis.toNanos - System.nanoTime()).nanos)
      silent.foreach(noteAnswer)
      silent.flatMap(keepAlive).flatMap(_.robotHealth).flatMap(_.bootId) should not contain 2

      val back = gateway.await(5.seconds) { heard =>
        noteAnswer(heard)
        keepAlive(heard).flatMap(_.robotHealth).filter(_.bootId.contains(2)).map(_ -> System.nanoTime())
      }
      val (health, heardAt) = back.getOrElse(fail("the robot did not come back"))
      (heardAt - cutAt).nanos should be >= 1.second
      health.uptimeMs.get should be < uptimeBefore

      result(gateway, address, "system", "ping") should matchPattern { case Right(Some(UInt(_))) => }
      gateway.collectFor(300.millis).foreach(noteAnswer)
      answered shouldBe false
      val view = state(robot)
      view.online shouldBe true
      view.bootId shouldBe 2
      view.stats.powerCycles shouldBe 1
      view.stats.droppedWhileOff should be >= 1L
      stop(robot)
    }

    "use the module's 4 s boot delay by default" in withGateway { gateway =>
      SimulatedRobot.PowerCycle().bootDelay shouldBe 4.seconds
      SimulatedRobotSettings(FirmwareSettings(robotId = 1), gateway.address).receivePort shouldBe 3838
      SimulatedRobotSettings(FirmwareSettings(robotId = 1), gateway.address).resetBootDelay shouldBe 4.seconds
      val (robot, _) = start(settings(gateway, FirmwareSettings(robotId = 6)))
      robot ! SimulatedRobot.PowerCycle()
      val off = state(robot)
      off.online shouldBe false
      off.onlineAgainIn.get should (be > 3.seconds and be <= 4.seconds)
      stop(robot)
    }

    "answer system.reset, then restart and stay silent while its module boots" in withGateway { gateway =>
      val firmware = FirmwareSettings(robotId = 8)
      val (robot, address) = start(settings(gateway, firmware).copy(resetBootDelay = 500.millis))
      result(gateway, address, "system", "reset") shouldBe ok
      val off = state(robot)
      off.online shouldBe false
      off.bootId shouldBe 2
      gateway.await(5.seconds)(h => keepAlive(h).flatMap(_.robotHealth).flatMap(_.bootId).filter(_ == 2)) shouldBe Some(
        2)
      state(robot).online shouldBe true
      stop(robot)
    }

    "take GameController packets on its own socket" in withGateway { gateway =>
      val packet = naogateway.wire.gamecontroller.GameControllerVectors.bytes("v8-playing.bin")
      // Team 1 plays in no vector packet, so the robot sends no return packet to anyone's port 3838.
      val (robot, address) = start(settings(gateway, FirmwareSettings(robotId = 4, teamId = 1)))
      gateway.send(packet, address)
      eventually(timeout(5.seconds)) {
        state(robot).firmware.gameControllerPackets shouldBe 1
      }
      stop(robot)
    }

    "work straight on the socket without the module model" in withGateway { gateway =>
      val (robot, address) = start(settings(gateway, FirmwareSettings(robotId = 11)).copy(faithfulLink = false))
      result(gateway, address, "heartbeat", "probe") shouldBe Left("unknown method: heartbeat.probe")
      gateway.await(2.seconds)(keepAlive).map(_.robotId) shouldBe Some(11)
      val view = state(robot)
      view.module shouldBe None
      view.cpu shouldBe None
      stop(robot)
    }

    "lose datagrams in the modelled module buffer in a burst, but none of the same datagrams sent slowly" in withGateway {
      gateway =>
        val (robot, address) = start(settings(gateway, FirmwareSettings(robotId = 9)))
        val frames = (0 until 38).map { i =>
          TestGateway.request("speech", "say", Vector(Text(f"$i%03d" + "x" * 990)), 1000L + i)
        }
        frames.foreach(_.length should (be > 1000 and be <= WireLimits.MaxDatagramBytes))

        def replyIds(heard: Vector[Heard]): Vector[Int] =
          heard.flatMap(_.contents).flatMap(_.rpcResponse).flatMap(_.callId)
        // One every 500 ms: each is read and handled long before the next arrives, even when the robot's actor
        // stalls for a while (two of them in the module's buffer at once would not fit).
        var calmReplies = frames.take(8).toVector.flatMap { frame =>
          gateway.send(frame, address)
          replyIds(gateway.collectFor(500.millis))
        }
        // A reply may come after its own window; the last one has no later window of its own.
        val deadline = 5.seconds.fromNow
        while (calmReplies.distinct.size < 8 && deadline.hasTimeLeft())
          calmReplies ++= replyIds(gateway.collectFor(100.millis))
        calmReplies.sorted shouldBe (1000 until 1008).toVector
        val calm = state(robot)
        calm.said.size shouldBe 8
        calm.module.get.lost shouldBe 0
        calm.module.get.overwritten shouldBe 0

        // The other 30 back to back: one 1 kB datagram fills most of the 1400-byte buffer.
        frames.drop(8).foreach(gateway.send(_, address))
        // The socket's buffer takes the whole burst; the snapshot is read once the robot has taken every datagram in.
        val crowded = eventually(timeout(10.seconds)) {
          val view = state(robot)
          view.stats.received shouldBe 38
          view
        }
        val module = crowded.module.get
        module.arrived shouldBe 38
        (module.lost + module.overwritten) should be > 0L
        crowded.said.size should be < 38
        stop(robot)
    }

    "hand secure-stream segments to its stream hook and answer the frames they carry through it" in withGateway {
      gateway =>
        // A stand-in endpoint: delivers each data segment's payload, wraps each frame in a segment numbered 0.
        final case class Unwrap(segments: Int) extends RobotStream {
          def receive(segment: Array[Byte], now: Long): RobotStream.Step =
            RobotStream.Step(Unwrap(segments + 1), Vector.empty, Vector(segment.drop(2)).filter(_.nonEmpty))
          def send(frame: Array[Byte], now: Long): RobotStream.Step =
            RobotStream.Step(this, Vector(Array[Byte](0, 0) ++ frame), Vector.empty)
          def tick(now: Long): RobotStream.Step = RobotStream.Step(this, Vector.empty, Vector.empty)
          def nextTimerAt: Option[Long] = None
        }
        val hooked = settings(gateway, FirmwareSettings(robotId = 12)).copy(stream = Some(_ => Unwrap(0)))
        val (robot, address) = start(hooked)
        gateway.send(Array[Byte](0, 20) ++ TestGateway.request("system", "ping", Vector.empty, 77), address)
        val reply = gateway.await(3.seconds) { heard =>
          if (heard.bytes.length > 2 && heard.bytes(0) == 0 && heard.bytes(1) == 0)
            MessageContents.decodeFrame(heard.bytes.drop(2)).toOption.flatMap(_._2.rpcResponse).filter(
              _.callId.contains(77))
          else None
        }
        reply shouldBe defined
        state(robot).stats.streamSegments shouldBe 1
        stop(robot)

        val (plain, plainAddress) = start(settings(gateway, FirmwareSettings(robotId = 13)))
        gateway.send(Array[Byte](0, 20) ++ TestGateway.request("system", "ping", Vector.empty, 78), plainAddress)
        val heard = gateway.collectFor(500.millis)
        val frames =
          heard.flatMap(h => h.contents.toVector ++ MessageContents.decodeFrame(h.bytes.drop(2)).toOption.map(_._2))
        frames.flatMap(_.rpcResponse).flatMap(_.callId) should not contain 78
        state(plain).stats.streamSegments shouldBe 1
        stop(plain)
    }
  }
}
