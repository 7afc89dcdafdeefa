package naogateway.sim

import java.net.InetSocketAddress

import org.scalatest.EitherValues
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.proto._
import naogateway.wire._

import scala.concurrent.duration._

class RobotFirmwareSpec extends AnyWordSpec with Matchers with EitherValues {

  private val ms = 1000000L
  private val gateway = new InetSocketAddress("127.0.0.1", 11011)
  private val settings = FirmwareSettings(robotId = 7, teamId = 12, role = "keeper")

  private def frames(out: Seq[Outgoing]): Seq[MessageContents] =
    out.map(o => MessageContents.decodeFrame(o.bytes).value._2)

  private def call(state: FirmwareState, module: String, method: String, params: Vector[RpcValue], id: Long, at: Long)
      : (FirmwareState, Vector[RpcReply]) = {
    val request = MessageContents(0, rpcRequest = Some(RpcCall(module, method, params, Some(id)).toProto))
    val (s, out) = RobotFirmware.receive(state, MessageContents.encodeFrame(request).value, gateway, at)
    (s, frames(out).flatMap(_.rpcResponse).map(RpcReply.fromProto).toVector)
  }

  private def stand(at: Long): FirmwareState = {
    val (s, _) = call(RobotFirmware.boot(settings, 0), "motion", "posture", Vector(RpcValue.Text("stand")), 1, at)
    RobotFirmware.advance(s, at + settings.standUpTime.toNanos)._1
  }

  "The simulated firmware" should {
    "send a keep-alive every 200 ms that decodes into the expected Status" in {
      var s = RobotFirmware.boot(settings, 0)
      val keepAlives = (0 to 1000 by 10).flatMap { t =>
        val (next, out) = RobotFirmware.advance(s, t * ms)
        s = next
        frames(out).filter(_.status.isDefined).map(t -> _)
      }
      keepAlives.map(_._1) shouldBe (0 to 1000 by 200)
      val (_, first) = keepAlives.head
      first.robotId shouldBe 7
      val status = first.status.get
      status.teamID shouldBe Some(12)
      status.activeRole shouldBe Some("keeper")
      status.activeAgent shouldBe Some("SimAgent")
      status.currentState shouldBe Some("sit")
      status.robotPosition.flatMap(_.x) shouldBe Some(-1000)
      first.robotHealth.flatMap(_.batteryVoltage) shouldBe Some(12.4f)
      first.robotHealth.flatMap(_.bootId) shouldBe Some(1)
    }
    "add servo telemetry to one keep-alive a second, from the robot's emulated bus or the given source (protocol.md 6.8)" in {
      def run(settings: FirmwareSettings, until: Int): Seq[(Int, MessageContents)] = {
        var s = RobotFirmware.boot(settings, 0)
        (0 to until by 10).flatMap { t =>
          val (next, out) = RobotFirmware.advance(s, t * ms)
          s = next
          frames(out).filter(_.status.isDefined).map(t -> _)
        }
      }
      val keepAlives = run(settings, 2400)
      keepAlives.filter(_._2.servoTelemetry.isDefined).map(_._1) shouldBe Seq(0, 1000, 2000)
      val model = keepAlives.head._2.servoTelemetry.get.servos
      model.map(_.id) shouldBe (1 to 18)
      model.foreach { servo =>
        servo.position.get should (be >= 0 and be <= 1023)
        servo.voltage shouldBe Some(124) // the bus reads the 12.4 V battery, in tenths
        servo.temperature.get should (be >= 20 and be < 70) // warm, below the AX-12A's 70 °C limit
        servo.silent shouldBe None
      }
      // A source instead of the robot's bus, at its own period; and off.
      val bus = () => Seq(ServoState(1, Some(300), Some(-5), Some(119), Some(50)), ServoState(2, silent = Some(true)))
      val fromBus = run(settings.copy(servoSource = Some(bus), servoTelemetryInterval = 400.millis), 1000)
      fromBus.filter(_._2.servoTelemetry.isDefined).map(_._1) shouldBe Seq(0, 400, 800)
      fromBus.head._2.servoTelemetry.get.servos shouldBe bus()
      run(settings.copy(servoTelemetryInterval = scala.concurrent.duration.Duration.Zero), 1000)
        .flatMap(_._2.servoTelemetry) shouldBe empty
    }

    "answer every documented call and an unknown method with an error" in {
      val s0 = RobotFirmware.boot(settings, 0)
      call(s0, "system", "battery", Vector.empty, 5, 1 * ms)._2 shouldBe Vector(
        RpcReply(Right(Some(RpcValue.Number(12.4f))), Some(5)))
      call(s0, "system", "ping", Vector.empty, 6, 1500 * ms)._2 shouldBe Vector(
        RpcReply(Right(Some(RpcValue.UInt(1500))), Some(6)))
      call(s0, "motion", "getPosture", Vector.empty, 7, ms)._2 shouldBe Vector(
        RpcReply(Right(Some(RpcValue.Text("sit"))), Some(7)))
      call(s0, "speech", "say", Vector(RpcValue.Text("hello")), 8, ms)._1.said shouldBe Vector("hello")
      call(s0, "nothing", "here", Vector.empty, 9, ms)._2 shouldBe Vector(RpcReply(Left("unknown method: nothing.here"),
          Some(9)))
      call(s0, "motion", "head", Vector(RpcValue.Text("x")), 10, ms)._2.head.result.left.value should startWith(
        "bad parameters")
      call(s0, "motion", "head", Vector(RpcValue.Number(3f), RpcValue.Number(0f)), 11, ms)._2.head.result.left
        .value should startWith("out of range")
      val (headed, ok) = call(s0, "motion", "head", Vector(RpcValue.Number(0.5f), RpcValue.Number(-0.2f)), 12, ms)
      ok shouldBe Vector(RpcReply(Right(Some(RpcValue.Flag(true))), Some(12)))
      headed.head._1 shouldBe 0.5 +- 1e-6
    }
    "take realistic time to stand up, and reply when the motion ends" in {
      val s0 = RobotFirmware.boot(settings, 0)
      val (moving, immediate) = call(s0, "motion", "posture", Vector(RpcValue.Text("stand")), 3, 10 * ms)
      immediate shouldBe empty
      moving.posture shouldBe Posture.Moving
      call(moving, "motion", "posture", Vector(RpcValue.Text("sit")), 4, 20 * ms)._2.head.result.left.value shouldBe "busy: moving"
      val (early, none) = RobotFirmware.advance(moving, 1000 * ms)
      frames(none).flatMap(_.rpcResponse) shouldBe empty
      early.posture shouldBe Posture.Moving
      val (stood, out) = RobotFirmware.advance(early, 1510 * ms)
      frames(out).flatMap(_.rpcResponse).map(RpcReply.fromProto) shouldBe Vector(
        RpcReply(Right(Some(RpcValue.Text("stand"))), Some(3)))
      stood.posture shouldBe Posture.Stand
    }
    "refuse to walk while sitting" in {
      val s0 = RobotFirmware.boot(settings, 0)
      call(s0, "motion", "walk", Vector(RpcValue.Number(0.1f), RpcValue.Number(0f), RpcValue.Number(0f)), 1, ms)._2.head
        .result.left.value shouldBe "not standing: sit"
    }
    "stop walking by itself when the walk lease is not refreshed" in {
      val standing = stand(0)
      val t0 = standing.now
      val walkParams = Vector(RpcValue.Number(0.2f), RpcValue.Number(0f), RpcValue.Number(0f))
      val (walking, _) = call(standing, "motion", "walk", walkParams, 2, t0)
      walking.posture shouldBe Posture.Walking
      val (refreshed, _) =
        call(RobotFirmware.advance(walking, t0 + 400 * ms)._1, "motion", "walk", walkParams, 3, t0 + 400 * ms)
      RobotFirmware.advance(refreshed, t0 + 800 * ms)._1.posture shouldBe Posture.Walking
      val stopped = RobotFirmware.advance(refreshed, t0 + 901 * ms)._1
      stopped.posture shouldBe Posture.Stand
      // 0.2 m/s for 0.9 s of leased walking, and not a step more.
      (stopped.pose.x - standing.pose.x) shouldBe 0.18 +- 0.001
      RobotFirmware.advance(stopped, t0 + 5000 * ms)._1.pose.x shouldBe stopped.pose.x
    }
    "drain the battery faster while walking" in {
      val standing = stand(0)
      val idle = RobotFirmware.advance(standing, standing.now + 10000 * ms)._1
      var walking = standing
      (0 until 25).foreach { i =>
        walking = call(walking, "motion", "walk",
          Vector(RpcValue.Number(0.1f), RpcValue.Number(0f), RpcValue.Number(0f)), i.toLong,
          standing.now + i * 400 * ms)._1
      }
      walking = RobotFirmware.advance(walking, standing.now + 10000 * ms)._1
      (standing.battery - walking.battery) should be > 5 * (standing.battery - idle.battery)
    }
    "recharge a low battery while sitting, up to sitChargeUpTo, not while standing (a team swapping a held robot's)" in {
      val low = RobotFirmware.boot(settings.copy(initialBattery = 10.7), 0)
      val sat = RobotFirmware.advance(low, 70000 * ms)._1
      sat.posture shouldBe Posture.Sit
      sat.battery shouldBe (10.7 + 70 * settings.sitChargePerSecond - 70 * settings.idleDrainPerSecond) +- 0.001
      // Above the middleware's battery-ok (11.0 V) in 70 s: the hold clears by itself.
      sat.battery should be > 11.0
      RobotFirmware.advance(sat, 3600000 * ms)._1.battery shouldBe settings.sitChargeUpTo +- 1e-9
      val standing = stand(0)
      RobotFirmware.advance(standing, standing.now + 10000 * ms)._1.battery should be < standing.battery
    }
    "answer every optionPull with its whole list in one frame, to the sender, in the command's header form (protocol.md 8)" in {
      val fuRemote = new InetSocketAddress("127.0.0.9", 11012)
      val pull = MessageContents(0, debuggingCommands = Some(DebuggingCommands(optionPull = Some(true))))
      val enable = MessageContents(0,
        debuggingCommands = Some(DebuggingCommands(optionEnable = Some(DebuggingOptionNames(Seq("status"))))))
      val (on, _) =
        RobotFirmware.receive(RobotFirmware.boot(settings, 0), MessageContents.encodeFrame(enable).value, gateway, ms)
      (1 to 2).foldLeft(on) { (s, i) =>
        val (next, out) =
          RobotFirmware.receive(s, MessageContents.encodeFrame(pull, HeaderForm.Compact).value, fuRemote, (1 + i) * ms)
        val pushes = out.filter(o => frames(Seq(o)).head.debuggingCommands.isDefined)
        pushes should have size 1
        MessageContents.decodeFrame(pushes.head.bytes).value._1.form shouldBe HeaderForm.Compact
        pushes.head.to match {
          case Destination.ReplyTo(to) => to.getAddress shouldBe fuRemote.getAddress
          case other                   => fail(s"sent to $other, not to the sender")
        }
        val options = frames(pushes).head.debuggingCommands.get.optionPush.get.options
        options.map(_.name) shouldBe RobotFirmware.OptionCatalogue.map(_._1)
        options.filter(_.enabled.contains(true)).map(_.name).toSet shouldBe Set("status.text", "status.table")
        next
      }
    }
    "offer its debug option list in under 1400 bytes and switch options by prefix" in {
      val s0 = RobotFirmware.boot(settings, 0)
      val pull = MessageContents(0, debuggingCommands = Some(DebuggingCommands(optionPull = Some(true))))
      val (_, out) = RobotFirmware.receive(s0, MessageContents.encodeFrame(pull).value, gateway, ms)
      val list = out.filter(o => frames(Seq(o)).head.debuggingCommands.isDefined)
      list should have size 1
      list.head.bytes.length should be <= WireLimits.MaxDatagramBytes
      frames(list).head.debuggingCommands.get.optionPush.get.options.map(_.name) shouldBe RobotFirmware.OptionCatalogue.map(
        _._1)

      val enable = MessageContents(0,
        debuggingCommands = Some(DebuggingCommands(optionEnable = Some(DebuggingOptionNames(Seq("havimo"))))))
      val (on, _) = RobotFirmware.receive(s0, MessageContents.encodeFrame(enable).value, gateway, 2 * ms)
      on.debugEnabled shouldBe Set("havimo.regions", "havimo.grid")
      val (_, camera) = RobotFirmware.advance(on, 100 * ms)
      val kinds = frames(camera)
      kinds.exists(_.havimoRegions.isDefined) shouldBe true
      kinds.exists(_.havimoGrid.isDefined) shouldBe true
      camera.foreach(_.bytes.length should be <= WireLimits.MaxDatagramBytes)
    }
    "ask to be woken only when something is due, whichever debug options are on" in {
      // A wake-up in the past after `advance` would make its driver spin on zero-delay timers.
      def enabled(prefix: String, at: Long): FirmwareState = {
        val enable = MessageContents(0,
          debuggingCommands = Some(DebuggingCommands(optionEnable = Some(DebuggingOptionNames(Seq(prefix))))))
        RobotFirmware.receive(RobotFirmware.boot(settings, 0), MessageContents.encodeFrame(enable).value, gateway, at)._1
      }
      for (prefix <- Seq("havimo", "camera", "status", "world", "motion")) {
        var s = enabled(prefix, 5000 * ms)
        (5000 to 7000 by 7).foreach { t =>
          s = RobotFirmware.advance(s, t * ms)._1
          withClue(s"$prefix at $t ms: ")(s.nextWakeUp should be > t * ms)
        }
      }
    }
    "come back from a reset as a new session with its debug options off" in {
      val s0 = RobotFirmware.boot(settings, 0)
      val enable = MessageContents(0,
        debuggingCommands = Some(DebuggingCommands(optionEnable = Some(DebuggingOptionNames(Seq("status"))))))
      val (on, _) = RobotFirmware.receive(s0, MessageContents.encodeFrame(enable).value, gateway, 5000 * ms)
      val (reset, replies) = call(on, "system", "reset", Vector.empty, 1, 6000 * ms)
      replies shouldBe Vector(RpcReply(Right(Some(RpcValue.Flag(true))), Some(1)))
      reset.bootId shouldBe 2
      reset.uptimeMillis shouldBe 0
      reset.debugEnabled shouldBe empty
    }
    "with a key, sign every frame it sends with its robot key under boot epoch and frame counter, the epoch rising at a reset" in {
      val key = SigningKey.fromHex("000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f").value
      val signing = settings.copy(signingKey = Some(key))
      def stamps(out: Seq[Outgoing]): Seq[Long] = out.filter(o => Datagram.isFuRemoteFrame(o.bytes)).map { o =>
        val header = FumanoidsFrame.decodeHeader(o.bytes).value
        FrameSigning.verifyFrame(o.bytes, header, key.robotKey(7), SignedLink.FromRobot(7)).value.timestamp
      }
      def request(c: MessageContents, ts: Long) =
        FrameSigning.signFrame(c, HeaderForm.Legacy, key.robotKey(7), SignedLink.ToRobot(7, 1), ts).value
      val (s1, first) = RobotFirmware.advance(RobotFirmware.boot(signing, 0), 0)
      val (s2, second) = RobotFirmware.advance(s1, 200 * ms)
      stamps(first ++ second) shouldBe Seq(FrameSigning.robotTimestamp(1, 0), FrameSigning.robotTimestamp(1, 1))
      val reset = MessageContents(0, rpcRequest = Some(RpcCall("system", "reset", Vector.empty, Some(3L)).toProto))
      val (s3, answered) = RobotFirmware.receive(s2, request(reset, 1000L), gateway, 300 * ms)
      stamps(answered) shouldBe Seq(FrameSigning.robotTimestamp(1, 2))
      s3.bootId shouldBe 2
      // The next session's frames sort above every frame of the one before, whatever its frame counter reached.
      stamps(RobotFirmware.advance(s3, 400 * ms)._2) shouldBe Seq(FrameSigning.robotTimestamp(2, 0))
      s3.stats.refusedSignatures shouldBe empty
    }
    "with a key, act only on the gateway's signed, newer frames and count the others by kind" in {
      val key = SigningKey.fromHex("000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f").value
      val other = SigningKey.fromHex("ff0102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f").value
      val s0 = RobotFirmware.boot(settings.copy(signingKey = Some(key)), 0)
      val stand = MessageContents(0,
        rpcRequest = Some(RpcCall("motion", "posture", Vector(RpcValue.Text("stand")), Some(4L)).toProto))
      def signed(ts: Long, k: RobotKey = key.robotKey(7), l: SignedLink = SignedLink.ToRobot(7, 1)) =
        FrameSigning.signFrame(stand, HeaderForm.Legacy, k, l, ts).value
      // Unsigned; another team's key; the robot's own direction; an earlier boot epoch; robot 5's key and id.
      val attempts = Vector(
        MessageContents.encodeFrame(stand).value,
        signed(50L, other.robotKey(7)),
        signed(50L, l = SignedLink.FromRobot(7)),
        signed(50L, l = SignedLink.ToRobot(7, 0)),
        signed(50L, key.robotKey(5), SignedLink.ToRobot(5, 1))
      )
      val refused = attempts.foldLeft(s0) { (s, bytes) =>
        val (next, out) = RobotFirmware.receive(s, bytes, gateway, ms)
        out.flatMap(o => MessageContents.decodeFrame(o.bytes).toOption).flatMap(_._2.rpcResponse) shouldBe empty
        next
      }
      refused.stats.refusedSignatures shouldBe Map("unsigned" -> 1L, "bad signature" -> 4L)
      refused.change shouldBe None
      val (moving, _) = RobotFirmware.receive(refused, signed(100L), gateway, 2 * ms)
      moving.change.map(_.target) shouldBe Some(Posture.Stand)
      val (replayed, _) = RobotFirmware.receive(moving, signed(100L), gateway, 3 * ms)
      replayed.stats.refusedSignatures.get("replayed") shouldBe Some(1L)
      // Through the secure stream nothing is signed (protocol.md 6.7): the stream's payloads count as they come.
      val (viaStream, _) =
        RobotFirmware.receive(refused, MessageContents.encodeFrame(stand).value, gateway, 4 * ms, viaStream = true)
      viaStream.change.map(_.target) shouldBe Some(Posture.Stand)
    }
    "see the ball ahead in the middle of the image and lose it when looking away" in {
      val pose = Pose(0, 0, 0)
      val ahead = Scene.regions(Scene(1.0, 0.0), pose, 0, -0.3)
      val ball = ahead.find(_.colour == Scene.BallColour).get
      ball.centreX shouldBe 80.0 +- 2.0
      Scene.regions(Scene(1.0, 0.0), pose, 1.5, -0.3).exists(_.colour == Scene.BallColour) shouldBe false
      val left = Scene.regions(Scene(1.0, 0.3), pose, 0, -0.3).find(_.colour == Scene.BallColour).get
      left.centreX should be < ball.centreX
      for (r <- ahead) {
        r.maxX should be < HaViMo.ImageWidth
        r.maxY should be < HaViMo.ImageHeight
      }
    }
  }

  "The simulated firmware" should {
    "answer the GameController it heard as a robot of that version does: version, port and content" in {
      import naogateway.wire.gamecontroller._
      val gc = new InetSocketAddress("127.0.0.9", 40123)
      val robot = RobotFirmware.boot(settings.copy(playerNumber = 3), 0)
      def answers(file: String): Vector[Outgoing] =
        RobotFirmware.receive(robot, GameControllerVectors.bytes(file), gc, 10 * ms)._2.filter(o =>
          Datagram.isGameControllerReturn(o.bytes))
      def to(o: Outgoing) = o.to match {
        case Destination.ReplyTo(a) => (a.getAddress.getHostAddress, a.getPort)
        case other                  => fail(s"not a reply: $other")
      }
      Seq("v20-playing.bin", "v20-initial-second-half.bin", "v19-playing.bin").foreach { file =>
        val hsl = answers(file)
        withClue(file) { hsl.map(to) shouldBe Vector(("127.0.0.9", 3939)) }
        hsl.head.bytes.length shouldBe GameControllerCodec.StatusPacketBytes
        val status = GameControllerCodec.decodeStatus(hsl.head.bytes).fold(e => fail(e.describe), identity)
        (status.player, status.team, status.fallen) shouldBe ((3, 12, false))
        status.pose._1 shouldBe (robot.pose.x * 1000).toFloat
      }
      val v12 = answers("v12-playing.bin")
      v12.map(to) shouldBe Vector(("127.0.0.9", 3939))
      GameControllerCodec.decodeReturn(v12.head.bytes) shouldBe Right(ReturnData(12, 3, ReturnMessage.Alive))
      val v8 = answers("v8-playing.bin")
      v8.map(to) shouldBe Vector(("127.0.0.9", 3838))
      GameControllerCodec.decodeReturn(v8.head.bytes) shouldBe Right(ReturnData(12, 3, ReturnMessage.Alive))
      answers("v7-playing.bin") shouldBe empty
      // A packet naming neither team as the robot's is not answered.
      RobotFirmware.receive(RobotFirmware.boot(settings.copy(teamId = 99), 0),
        GameControllerVectors.bytes("v19-playing.bin"),
        gc, 10 * ms)._2.filter(o => Datagram.isGameControllerReturn(o.bytes)) shouldBe empty
    }
  }
}
