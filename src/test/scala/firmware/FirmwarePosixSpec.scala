package firmware

import java.io.File
import java.net.{DatagramPacket, DatagramSocket, InetSocketAddress, SocketTimeoutException}
import java.nio.charset.StandardCharsets
import java.nio.file.Files
import java.util.concurrent.{ConcurrentLinkedQueue, TimeUnit}
import java.util.concurrent.atomic.AtomicInteger

import scala.concurrent.duration._
import scala.concurrent.Await
import scala.jdk.CollectionConverters._
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit, TestProbe}
import akka.actor.typed.ActorRef
import akka.stream.KillSwitches
import akka.stream.scaladsl.{Keep, Sink}
import org.scalatest.BeforeAndAfterAll
import org.scalatest.wordspec.AnyWordSpecLike

import apps.RobotRig
import naogateway.integration.TestStream
import naogateway.testkit.{TempFiles, TestLoopback}
import naogateway.wire.gamecontroller.GameControllerVectors
import naogateway.proto.Request
import naogateway.wire.{MessageContents, Posture, RpcValue}
import naogateway.api.{RobotSnapshot, VisionFrame}
import naogateway.gateway.robot.StreamActor
import robotmiddleware.RobotInterface

/** The gateway's configuration for the C robots: stream window 4 (the robots are built with WINDOW=4), one robot that
  * must sign (the team key makes `required` every robot's default) and three development builds named with `signing =
  * off` (protocol.md 6.7: an unsigned robot is accepted only where the config says so by name).
  */
object FirmwarePosixSpec {
  val KeyHex = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f"
  val SignedId = 63

  /** The signing robot's address, fixed before the gateway starts: the configuration names it. */
  lazy val signedAddress: String = TestLoopback.address().getHostAddress

  /** The development builds' ids and addresses, fixed before the gateway starts for the same reason. */
  val PlainId = 61
  val StreamId = 62
  val LinkId = 64
  val BusId = 65
  val ExampleId = 66
  lazy val developmentAddresses: Map[Int, String] =
    Seq(PlainId, StreamId, LinkId, BusId, ExampleId).map(id => id -> TestLoopback.address().getHostAddress).toMap

  private def developmentEntries: String =
    developmentAddresses.map { case (id, a) => "{ id = " + id + ", address = \"" + a + "\", signing = off }" }.mkString(
      ", ")

  def config: String =
    s"""naogateway {
       |  link { bind-address = "127.0.0.1", robot-port = 0 }
       |  game-controller.enabled = off
       |  stream.window = 4
       |  signing.key = "$KeyHex"
       |  robots = [ { id = $SignedId, address = "$signedAddress", signing = required }, $developmentEntries ]
       |}
       |""".stripMargin
}

/** The C library's posix robot (firmware/testrobot/robot.c over host UDP sockets, built with `make native WINDOW=4`)
  * against a real gateway and middleware on loopback, each robot at its own 127.x address receiving on 3838, as the
  * Python conformance robot is driven in DocRobotConformanceSpec. Cancelled with the reason when make, a C compiler or
  * nanopb is missing (bash firmware/setup.sh installs them).
  */
class FirmwarePosixSpec
    extends ScalaTestWithActorTestKit(FirmwarePosixSpec.config)
    with AnyWordSpecLike
    with LogCapturing
    with BeforeAndAfterAll {
  import FirmwarePosixSpec._
  import apps.RobotCalls._

  override def afterAll(): Unit = {
    rig.close()
    super.afterAll()
  }

  private lazy val robotBinary: File = {
    FirmwareBuild.make(this, Seq("native"), Map("WINDOW" -> "4"))
    new File(FirmwareBuild.dir, "build/posix-w4/robot")
  }
  private val rig = new RobotRig(testKit, "firmware")
  private def gatewayPort: Int = rig.gatewayAddress.getPort
  private def client: RobotInterface = rig.client

  /** One C robot process and what the gateway published about it. */
  private final class CRobot(val id: Int, val address: String, args: Seq[String] = Nil,
      env: Map[String, String] = Map.empty) {
    val log = new File(FirmwareBuild.dir, s"build/spec/robot-$id.log")
    val epochFile = new File(FirmwareBuild.dir, s"build/spec/robot-$id.epoch")
    log.getParentFile.mkdirs()
    val process: Process = {
      // Without a key the robot is started as a development build by name (unsigned, RobotHealth.development).
      val trust = if (args.exists(a => a.startsWith("key=") || a.startsWith("team_key="))) Nil
      else Seq("development")
      val b = new ProcessBuilder((Seq(robotBinary.getPath, s"id=$id", "team=12", "player=3",
          s"gateway=127.0.0.1:$gatewayPort", s"epoch=${epochFile.getPath}",
          "run_ms=90000", "reset_ms=1000") ++ trust ++ args).asJava).redirectErrorStream(true).redirectOutput(log)
      b.environment().put("FR_POSIX_BIND", s"$address:${TestLoopback.RobotReceivePort}")
      env.foreach { case (k, v) => b.environment().put(k, v) }
      rig.owned(b.start(), grace = 5.seconds)
    }
    val snapshots = new ConcurrentLinkedQueue[RobotSnapshot]()
    client.status(id).runWith(Sink.foreach(snapshots.add))
    def output: String = Try(new String(Files.readAllBytes(log.toPath), StandardCharsets.UTF_8)).getOrElse("")

    def awaitOnline(): Unit = {
      val online = rig.awaitOnline(id, 20.seconds)
      withClue(s"robot $id never came online; its output:\n$output\n") { online shouldBe true }
      rig.acquireAll(id, 10.seconds)
    }
  }

  /** Vision frames of `id` for at most `within`: regions and grids counted until both are seen. */
  private def visionFrames(id: Int, within: FiniteDuration): (Int, Int) = {
    val regions, grids = new AtomicInteger()
    val kill = client.vision(id, grid = true).viaMat(KillSwitches.single)(Keep.right).to(Sink.foreach {
      case _: VisionFrame.Regions => regions.incrementAndGet()
      case _: VisionFrame.Grid    => grids.incrementAndGet()
    }).run()
    poll(within)(regions.get() > 2 && grids.get() > 2)
    kill.shutdown()
    (regions.get(), grids.get())
  }

  /** The gateway's stream endpoint for robot `id`, subscribed to what it delivers. */
  private def streamOf(id: Int): (TestStream, TestProbe[StreamActor.Received]) =
    rig.streamOf(id).getOrElse(fail(s"the gateway does not know robot $id"))

  private lazy val plain: CRobot = {
    val r = new CRobot(PlainId, developmentAddresses(PlainId))
    r.awaitOnline()
    r
  }

  "The C library's posix robot" must {
    "send keep-alives with RobotHealth every 200 ms and come online" in {
      val r = plain
      val before = r.snapshots.size
      Thread.sleep(2000)
      val seen = r.snapshots.asScala.toVector
      (seen.size - before) should be >= 7
      val last = seen.last
      last.agent shouldBe Some("CAgent")
      last.teamId shouldBe Some(12)
      last.bootId shouldBe Some(1)
      last.posture shouldBe Some(Posture.Sit)
      last.batteryVoltage.get shouldBe 12.4 +- 0.1
      last.position shouldBe Some((-1000, 0, 0.0))
      last.uptimeMillis.get should be > 1000L
    }

    "serve every RPC method of protocol.md 7.2 and answer with the errors of 7.4" in {
      val id = plain.id
      result(client.call(id, "system", "ping")) should matchPattern { case Right(Some(RpcValue.UInt(_))) => }
      result(client.call(id, "system", "battery")) should matchPattern {
        case Right(Some(RpcValue.Number(v))) if v > 12f && v < 12.6f =>
      }
      result(client.call(id, "motion", "getPosture")) shouldBe Right(Some(RpcValue.Text("sit")))
      robotError(result(client.walk(id, 0.1, 0, 0))) shouldBe "not standing: sit"
      // The middleware refuses it before sending (its walk/head limits); the robot's own check is test_protocol.c's.
      robotError(result(client.head(id, 0, 0.8))) shouldBe "out of range: tilt 0.8, allowed -0.6..0.5"
      result(client.head(id, 0.5, 0.2)).isRight shouldBe true
      result(client.arms(id, 0.1, 0.2, 0.3, 0.4)).isRight shouldBe true
      result(client.say(id, "hello from the gateway")).isRight shouldBe true
      robotError(result(client.call(id, "motion", "dance"))) shouldBe "unknown method: motion.dance"
      robotError(result(client.call(id, "motion", "walk", RpcValue.Number(0.1f), RpcValue.Number(0f)))) shouldBe
        "bad parameters: expected 3 numbers, got 2 parameter(s)"
      robotError(result(client.call(id, "motion", "posture", RpcValue.Text("fly")))) should startWith(
        "bad parameters: ")
      result(client.posture(id, Posture.Stand)) shouldBe Right(Posture.Stand)
      val started = System.nanoTime()
      result(client.posture(id, Posture.Crouch)) shouldBe Right(Posture.Crouch)
      (System.nanoTime() - started).nanos should be >= 400.millis
      val standing = client.posture(id, Posture.Stand)
      Thread.sleep(300)
      robotError(result(client.call(id, "motion", "posture", RpcValue.Text("sit")))) shouldBe "busy: moving"
      result(standing) shouldBe Right(Posture.Stand)
      result(client.walk(id, 0.1, 0, 0)).isRight shouldBe true
      result(client.call(id, "motion", "getPosture")) shouldBe Right(Some(RpcValue.Text("walking")))
      result(client.stop(id)).isRight shouldBe true
      result(client.call(id, "motion", "getPosture")) shouldBe Right(Some(RpcValue.Text("stand")))
    }

    "run as the example a team starts from (examples/hello_robot.c): online, keep-alives, motion.head answered" in {
      FirmwareBuild.make(this, Seq("example"), Map("WINDOW" -> "4"))
      val log = new File(FirmwareBuild.dir, s"build/spec/robot-$ExampleId.log")
      log.getParentFile.mkdirs()
      val b = new ProcessBuilder(new File(FirmwareBuild.dir, "build/posix-w4/hello_robot").getPath, s"id=$ExampleId",
        s"gateway=127.0.0.1:$gatewayPort", "development", "run_ms=60000").redirectErrorStream(true).redirectOutput(log)
      b.environment().put("FR_POSIX_BIND", s"${developmentAddresses(ExampleId)}:${TestLoopback.RobotReceivePort}")
      rig.owned(b.start(), grace = 5.seconds)
      def output = Try(new String(Files.readAllBytes(log.toPath), StandardCharsets.UTF_8)).getOrElse("")
      val snapshots = new ConcurrentLinkedQueue[RobotSnapshot]()
      client.status(ExampleId).runWith(Sink.foreach(snapshots.add))
      withClue(s"the example's output:\n$output\n") {
        rig.awaitOnline(ExampleId, 20.seconds) shouldBe true
        rig.acquireAll(ExampleId, 10.seconds)
        // Its keep-alives carry what its health callback fills in.
        poll(5.seconds)(snapshots.asScala.exists(s =>
            s.posture.contains(Posture.Stand) && s.batteryVoltage.exists(v => math.abs(v - 12.4) < 0.01))) shouldBe true
        result(client.head(ExampleId, 0.5, 0.2)).isRight shouldBe true
        // Its one command: everything else is unknown to it.
        robotError(result(client.walk(ExampleId, 0.1, 0, 0))) shouldBe "unknown method: motion.walk"
      }
    }

    "offer its debug options and send HaViMo2 region and grid frames while enabled" in {
      val (regions, grids) = visionFrames(plain.id, 10.seconds)
      regions should be > 2
      grids should be > 2
    }

    "answer GameController packets of versions 7, 8, 12, 19 and 20 with the return packet of each" in {
      val r = plain
      val gcAddress = TestLoopback.address().getHostAddress
      val gc = new DatagramSocket(new InetSocketAddress(gcAddress, 3838))
      val gc3939 = new DatagramSocket(new InetSocketAddress(gcAddress, 3939))
      Seq(gc, gc3939).foreach { s => rig.owned(s); s.setSoTimeout(600) }
      val robotAt = new InetSocketAddress(r.address, 3838)
      def replies(on: DatagramSocket): Vector[String] = Iterator.continually {
        val buf = new Array[Byte](64)
        val p = new DatagramPacket(buf, buf.length)
        try { on.receive(p); Some(buf.take(p.getLength).map("%02X".format(_)).mkString(" ")) }
        catch { case _: SocketTimeoutException => None }
      }.takeWhile(_.isDefined).flatten.take(4).toVector
      def send(packet: Array[Byte]): Unit = gc.send(new DatagramPacket(packet, packet.length, robotAt))
      // One 2014 round: version 8 then 7. Only version 8 is answered (10.3), team 12 player 3, "alive".
      send(GameControllerVectors.bytes("v8-playing.bin"))
      send(GameControllerVectors.bytes("v7-playing.bin"))
      replies(gc) shouldBe Vector("52 47 72 74 02 0C 03 02")
      // A version-7-only GameController, once version 8 has been silent for two rounds.
      Thread.sleep(1100)
      send(GameControllerVectors.bytes("v7-playing.bin"))
      replies(gc) shouldBe Vector("52 47 72 74 02 0C 03 02")
      // Version 12 (688 bytes) and 19 (198 bytes): answered at port 3939, with return versions 2 and 4.
      val v12 = new Array[Byte](688)
      "RGme".getBytes(StandardCharsets.US_ASCII).copyToArray(v12)
      v12(4) = 12; v12(9) = 3; v12(24) = 12; v12(24 + 332) = 7
      send(v12)
      replies(gc3939) shouldBe Vector("52 47 72 74 02 0C 03 02")
      val v19 = new Array[Byte](198)
      "RGme".getBytes(StandardCharsets.US_ASCII).copyToArray(v19)
      v19(4) = 19; v19(10) = 3; v19(18) = 7; v19(18 + 90) = 12
      send(v19)
      replies(gc3939) shouldBe Vector(
        "52 47 72 74 04 03 0C 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 80 BF 00 00 00 00 00 00 00 00")
      // Version 20 (158 bytes, RoboCup 2026; protocol.md 10.11): the same return packet, version 4 to 3939.
      val v20 = new Array[Byte](158)
      "RGme".getBytes(StandardCharsets.US_ASCII).copyToArray(v20)
      v20(4) = 20; v20(10) = 3; v20(18) = 7; v20(18 + 70) = 12
      send(v20)
      replies(gc3939) shouldBe Vector(
        "52 47 72 74 04 03 0C 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 80 BF 00 00 00 00 00 00 00 00")
      // A packet for other teams only is not answered.
      v19(18) = 1; v19(18 + 90) = 2
      send(v19)
      replies(gc3939) shouldBe empty
      v20(18) = 1; v20(18 + 70) = 2
      send(v20)
      replies(gc3939) shouldBe empty
    }

    "re-sync after system.reset: a new session with bootId 2, its options enabled again" in {
      val r = plain
      visionFrames(r.id, 10.seconds)._1 should be > 0
      val kept = client.vision(r.id).viaMat(KillSwitches.single)(Keep.right).to(Sink.ignore).run()
      result(client.call(r.id, "system", "reset")) shouldBe Right(Some(RpcValue.Flag(true)))
      withClue(s"bootIds published: ${r.snapshots.asScala.flatMap(_.bootId).toSet}") {
        poll(15.seconds)(r.snapshots.asScala.exists(_.bootId.contains(2))) shouldBe true
      }
      // The gateway pulled the new session's option list and enabled havimo.regions again for the kept subscription.
      val after = new AtomicInteger()
      val k =
        client.vision(r.id).viaMat(KillSwitches.single)(Keep.right).to(Sink.foreach(_ => after.incrementAndGet())).run()
      poll(10.seconds)(after.get() > 2) shouldBe true
      k.shutdown()
      kept.shutdown()
      result(client.call(r.id, "system", "ping")) should matchPattern {
        case Right(Some(RpcValue.UInt(v))) if v < 60000 =>
      }
    }

    "sign every frame and act only on the gateway's signed ones when the robot requires signing" in {
      // With another key its frames are refused by the gateway (bad signature): it never comes online.
      val stranger = new CRobot(SignedId, signedAddress, Seq(s"key=${"5a" * 32}"))
      Thread.sleep(1500)
      Await.result(client.robots(), 5.seconds).exists(r => r.robotId == SignedId && r.online) shouldBe false
      stranger.process.destroy()
      stranger.process.waitFor(5, TimeUnit.SECONDS) shouldBe true
      // The robot key the gateway derives from its team key (robotctl keys 63), computed by the test-side signer.
      val r =
        new CRobot(SignedId, signedAddress, Seq(s"key=${Fusig2.hex(Fusig2.robotKey(Fusig2.unhex(KeyHex), SignedId))}"))
      r.awaitOnline()
      result(client.call(r.id, "system", "ping")) should matchPattern { case Right(Some(RpcValue.UInt(_))) => }
      robotError(result(client.call(r.id, "motion", "dance"))) shouldBe "unknown method: motion.dance"
      val (regions, _) = visionFrames(r.id, 10.seconds)
      regions should be > 0
      r.snapshots.asScala.last.agent shouldBe Some("CAgent")
    }

    "tell the program when the module reports the network lost, which then stops and sits" in {
      val linkFile = Files.createTempFile("firmware-link", ".lost").toFile
      linkFile.delete()
      TempFiles.cleaningUp(linkFile.toPath) {
        val r = new CRobot(LinkId, developmentAddresses(LinkId), env = Map("FR_POSIX_LINK" -> linkFile.getPath))
        r.awaitOnline()
        result(client.posture(r.id, Posture.Stand)) shouldBe Right(Posture.Stand)
        // The module reports the network lost for half a second (the posix port: the file exists), then back.
        Files.write(linkFile.toPath, Array.emptyByteArray)
        Thread.sleep(500)
        linkFile.delete()
        withClue(s"robot output:\n${r.output}\n") {
          poll(10.seconds)(result(client.call(r.id, "motion", "getPosture")) == Right(
            Some(RpcValue.Text("sit")))) shouldBe true
        }
      }
    }

    "serve its Dynamixel bus to the official DynamixelSDK through the gateway's bus bridge (protocol.md 6.9)" in {
      apps.zeromq.PythonEnv.python()
      apps.SdkBus.socat()
      // The robot reads the emulated bus (firmware/tools/busmodel.c) as its own; the gateway serves it on loopback.
      val base = {
        val free = new java.net.ServerSocket(0, 1, java.net.InetAddress.getLoopbackAddress)
        try free.getLocalPort - BusId
        finally free.close()
      }
      val bridge = spawn(naogateway.gateway.BusBridgeServer(rig.gateway,
          naogateway.gateway.BusBridgeSettings(enabled = true, basePort = base), None))
      val r = new CRobot(BusId, developmentAddresses(BusId), env = Map("FR_POSIX_BUS" -> "model"))
      try {
        r.awaitOnline()
        eventually(timeout(20.seconds)) { new java.net.Socket("127.0.0.1", base + BusId).close() }
        // The probe held the one tool's place; the bridge frees it when it sees the probe gone.
        Thread.sleep(1000)
        apps.SdkBus.throughPty(base + BusId) { device =>
          // Over the bridge a round trip crosses the link twice: the SDK's packet timeout is raised (README).
          val (code, out) = apps.SdkBus.run(device, Seq("--latency-ms", "250"))
          withClue(s"SDK:\n$out\nrobot output:\n${r.output}\n") {
            code shouldBe 0
            (1 to 18).foreach(id => out should include(s""""$id": 12"""))
          }
        }
      } finally testKit.stop(bridge)
    }

    "carry the stream both ways at 10 % loss with selective repeat: complete, in order, calls answered through it" in {
      val r = new CRobot(StreamId, developmentAddresses(StreamId),
        env = Map("FR_POSIX_LOSS" -> "10", "FR_POSIX_SEED" -> "62"))
      r.awaitOnline()
      val (stream, received) = streamOf(r.id)
      // 24 payloads of 1 to 1380 bytes to the robot, which echoes each through its own stream.
      val payloads = (0 until 24).map(i => Array.tabulate[Byte](1 + i * 60)(k => (0x50 + (i + k) % 40).toByte))
      val callId = 1000000 + scala.util.Random.nextInt(100000)
      val ping = MessageContents.encodeFrame(MessageContents(r.id,
          rpcRequest = Some(Request("system", "ping", callId = Some(callId))))).toOption.get
      payloads.take(12).foreach(p => stream.send(p))
      stream.send(ping)
      payloads.drop(12).foreach(p => stream.send(p))
      val echoes = Vector.newBuilder[Vector[Byte]]
      var answered = false
      val deadline = 30.seconds.fromNow
      var count = 0
      while ((count < payloads.size || !answered) && deadline.hasTimeLeft()) {
        Try(received.receiveMessage(deadline.timeLeft.max(1.milli))).toOption.foreach { m =>
          if (m.payload.length >= 2 && m.payload(0) == 0 && m.payload(1) == 42)
            MessageContents.decodeFrame(m.payload).toOption.foreach { case (_, c) =>
              if (c.rpcResponse.exists(_.callId.contains(callId))) answered = true
            }
          else { echoes += m.payload.toVector; count += 1 }
        }
      }
      val stats = createTestProbe[naogateway.wire.stream.StreamStats]()
      stream.stats(stats.ref)
      val seen = stats.receiveMessage(5.seconds)
      info(s"gateway's stream: $seen")
      withClue(s"robot output:\n${r.output}\n") {
        echoes.result() shouldBe payloads.map(_.toVector).toVector
        answered shouldBe true
      }
      // The loss was real: the gateway had to send some of its segments again.
      seen.retransmissions should be > 0L
    }
  }
}
