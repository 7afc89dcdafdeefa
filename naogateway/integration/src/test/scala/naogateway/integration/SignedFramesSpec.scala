package naogateway.integration

import java.net.{InetAddress, InetSocketAddress}
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._
import scala.util.Random

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.{GatewayAccess, RobotAccess}
import naogateway.api.{CallResult, GatewayEvent, LinkStats, RobotEvent, RobotSnapshot, RobotStatusUpdated, SigningState}
import naogateway.gateway.robot.RobotEffects
import naogateway.sim.network.ForgedFrames
import naogateway.testkit.{RelayCapture, TestLoopback}
import naogateway.wire._

/** A gateway that requires signed frames of one robot (docs/protocol.md 6.7), with a simulated robot that signs, and an
  * outsider that sends from that robot's own IP address: what the robot really says counts, nothing forged does.
  */
class SignedFramesSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {
  import SignedFramesSpec._

  private def call(c: RobotEffects.Connected, name: String, params: RpcValue*): CallResult = {
    val probe = createTestProbe[CallResult]()
    val (module, method) = name.span(_ != '.')
    c.response ! RobotAccess.Call(RpcCall(module, method.drop(1), params.toVector), probe.ref)
    probe.receiveMessage(10.seconds)
  }

  /** A gateway with the team key, requiring robot `robotId` at `ip` to sign (by default: no `signing` in its entry),
    * relaying every robot datagram to `relayPort` (a recorder); `more` are further entries of `robots`.
    */
  private def withGateway[A](robotId: Int, ip: InetAddress, relayPort: Int = 0, more: String = "")(
      test: GatewayFixture => A): A = {
    val relay =
      if (relayPort == 0) "" else s"fu-remote-relay { enabled = on, address = \"127.0.0.1\", port = $relayPort }"
    val f = new GatewayFixture(
      testKit,
      s"""robots = [ { id = $robotId, address = "${ip.getHostAddress}" } $more ]
         |signing.key = "$TeamKeyHex"
         |$relay""".stripMargin
    )
    try test(f)
    finally f.stop()
  }

  private def signing(firmware: naogateway.sim.FirmwareSettings) = firmware.copy(signingKey = Some(TeamKey))

  private def linkStats(f: GatewayFixture, robotId: Int): LinkStats = {
    val stats = createTestProbe[LinkStats]()
    f.robotAccess(robotId) ! RobotAccess.GetLinkStats(stats.ref)
    stats.receiveMessage(5.seconds)
  }

  private def snapshot(f: GatewayFixture, robotId: Int): RobotSnapshot = {
    val probe = createTestProbe[RobotSnapshot]()
    f.robotAccess(robotId) ! RobotAccess.GetSnapshot(probe.ref)
    probe.receiveMessage(5.seconds)
  }

  "A gateway requiring signatures" must {
    "answer a signed robot's calls, take its keep-alives, and sign what it sends; a robot set to off works unsigned" in {
      val ip = TestLoopback.address()
      val plainIp = TestLoopback.address()
      withGateway(31, ip, more = s""", { id = 32, address = "${plainIp.getHostAddress}", signing = off }""") { f =>
        val (robot, _) = f.robot(31, firmware = signing, at = ip)
        val (plain, _) = f.robot(32, at = plainIp)
        val signed = f.connect(31)
        call(signed, "system.ping").result.isRight shouldBe true
        call(signed, "motion.posture", RpcValue.Text("stand")).result shouldBe Right(Some(RpcValue.Text("stand")))
        f.awaitEvent(10.seconds) {
          case RobotStatusUpdated(s)
              if s.robotId == 31 && s.posture.contains(Posture.Stand) && s.batteryVoltage.exists(_ > 12.0) => ()
        }
        call(f.connect(32), "system.ping").result.isRight shouldBe true
        // The gateway signed every request and probe, and the robot took each one: nothing refused on either side.
        val view = f.view(robot)
        view.firmware.refusedSignatures shouldBe empty
        view.firmware.rpcCalls should be >= 2L
        view.posture shouldBe Posture.Stand
        linkStats(f, 31).rejected shouldBe empty
        snapshot(f, 31).online shouldBe true
        snapshot(f, 31).signing shouldBe SigningState.Signed
        snapshot(f, 32).signing shouldBe SigningState.Off
        f.view(plain).firmware.refusedSignatures shouldBe empty
        f.stats().rejected.keySet.intersect(SignatureKinds) shouldBe empty
      }
    }

    "let no forged frame from the robot's own address change the robot, and count each by kind" in {
      val ip = TestLoopback.address()
      val recorder = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      val outsider = DatagramChannel.open().bind(new InetSocketAddress(ip, 0))
      try withGateway(33, ip, recorder.getLocalAddress.asInstanceOf[InetSocketAddress].getPort) { f =>
          val (robot, _) = f.robot(33, firmware = signing, at = ip)
          call(f.connect(33), "system.ping").result.isRight shouldBe true
          val recorded = RelayCapture.frames(recorder, 33, 1.5.seconds)
          recorded.size should be >= 3
          val before = snapshot(f, 33)
          before.bootId shouldBe Some(1)
          val refusedBefore = f.stats().rejected.values.sum
          val batch = ForgedFrames.batch(33, recorded, WrongKey, perKind = 20, new Random(7))
          // Drain what came before, then send the forgeries and watch every event of the robot for a while.
          collect(f, 300.millis)
          batch.foreach(frame => outsider.send(ByteBuffer.wrap(frame), f.addresses.robots))
          val seen = collect(f, 2.seconds).filter {
            case e: RobotEvent => e.robotId == 33
            case _             => false
          }
          ForgedFrames.stateChanges(seen, truth = before) shouldBe 0
          seen.collect { case RobotStatusUpdated(s) => s } should not be empty // the real keep-alives went on
          val after = snapshot(f, 33)
          (after.online, after.bootId, after.posture) shouldBe ((true, Some(1), before.posture))
          after.batteryVoltage.get should be > 12.0
          // Every forged datagram refused exactly once, by its kind; the robot counts the same kinds.
          val refused = f.stats().rejected
          refused.values.sum - refusedBefore shouldBe batch.size
          refused("unsigned") shouldBe 20
          refused("bad signature") should be >= 20L
          refused("replayed") should be >= recorded.size.toLong
          refused("signature not last") should be >= recorded.size.toLong
          refused("malformed signature") should be >= recorded.size.toLong
          linkStats(f, 33).rejected.keySet should contain allElementsOf SignatureKinds
          // And the robot's calls still work.
          call(f.connect(33), "system.ping").result.isRight shouldBe true
          f.view(robot).firmware.refusedSignatures shouldBe empty
        }
      finally { recorder.close(); outsider.close() }
    }

    "leave a signing robot unmoved by requests the gateway did not sign" in {
      val ip = TestLoopback.address()
      withGateway(34, ip) { f =>
        val (robot, receivesAt) = f.robot(34, firmware = signing, at = ip)
        call(f.connect(34), "system.ping").result.isRight shouldBe true
        val outsider = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
        try {
          val stand = MessageContents(34,
            rpcRequest =
              Some(RpcCall("motion", "posture", Vector(RpcValue.Text("stand"))).copy(callId = Some(5L)).toProto))
          (1 to 5).foreach { i =>
            outsider.send(ByteBuffer.wrap(ForgedFrames.unsigned(stand)), receivesAt)
            outsider.send(
              ByteBuffer.wrap(FrameSigning.signFrame(stand, HeaderForm.Legacy, WrongKey.robotKey(34),
                  SignedLink.ToRobot(34, 1), Long.MaxValue - i).toOption.get),
              receivesAt
            )
          }
          eventually(timeout(10.seconds)) {
            f.view(robot).firmware.refusedSignatures shouldBe Map("unsigned" -> 5L, "bad signature" -> 5L)
          }
          f.view(robot).posture shouldBe Posture.Sit
        } finally outsider.close()
      }
    }
  }

  "Per-robot keys and boot epochs" must {
    "refuse a frame robot A signed when it comes as robot B's, and leave B as it was" in {
      val ipA = TestLoopback.address()
      val ipB = TestLoopback.address()
      val recorder = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      val outsider = DatagramChannel.open().bind(new InetSocketAddress(ipB, 0))
      try withGateway(35, ipA, recorder.getLocalAddress.asInstanceOf[InetSocketAddress].getPort,
          more = s""", { id = 36, address = "${ipB.getHostAddress}" }""") { f =>
          f.robot(35, firmware = signing, at = ipA)
          f.robot(36, firmware = signing, at = ipB)
          call(f.connect(35), "system.ping").result.isRight shouldBe true
          call(f.connect(36), "system.ping").result.isRight shouldBe true
          val fromA = RelayCapture.frames(recorder, 35, 1.second)
          fromA should not be empty
          // A's frames from B's address, once as they are and once with B's id in them (robotID is the first field).
          val asB = fromA.map { frame =>
            val header = FumanoidsFrame.decodeHeader(frame).toOption.get
            val relabelled = frame.clone()
            relabelled(header.form.headerBytes + 1) shouldBe 35
            relabelled(header.form.headerBytes + 1) = 36
            relabelled
          }
          val before = linkStats(f, 36).rejected.getOrElse("bad signature", 0L)
          (fromA ++ asB).foreach(frame => outsider.send(ByteBuffer.wrap(frame), f.addresses.robots))
          eventually(timeout(10.seconds)) {
            linkStats(f, 36).rejected.getOrElse("bad signature", 0L) - before shouldBe asB.size
          }
          val b = snapshot(f, 36)
          (b.online, b.signing, b.bootId) shouldBe ((true, SigningState.Signed, Some(1)))
          call(f.connect(36), "system.ping").result.isRight shouldBe true
        }
      finally { recorder.close(); outsider.close() }
    }

    "keep a robot online after it restarts with a higher boot epoch, signing to it under the new one" in {
      val ip = TestLoopback.address()
      withGateway(37, ip) { f =>
        val (robot, _) = f.robot(37, firmware = signing, at = ip)
        call(f.connect(37), "system.ping").result.isRight shouldBe true
        call(f.connect(37), "system.reset").result shouldBe Right(Some(RpcValue.Flag(true)))
        // Back after its module's boot delay, in boot epoch 2: its frames count again, and the gateway's reach it.
        eventually(timeout(30.seconds), interval(200.millis)) {
          val s = snapshot(f, 37)
          (s.online, s.bootId, s.signing) shouldBe ((true, Some(2), SigningState.Signed))
        }
        call(f.connect(37), "motion.posture", RpcValue.Text("stand")).result shouldBe
          Right(Some(RpcValue.Text("stand")))
        f.view(robot).firmware.refusedSignatures shouldBe empty
        linkStats(f, 37).rejected.get("replayed") shouldBe None
      }
    }

    "show a robot that must sign but sends unsigned frames as unsigned, not as offline" in {
      val ip = TestLoopback.address()
      withGateway(38, ip) { f =>
        f.robot(38, at = ip) // no key: every keep-alive unsigned
        eventually(timeout(10.seconds)) {
          val s = snapshot(f, 38)
          (s.online, s.signing) shouldBe ((false, SigningState.Unsigned))
          linkStats(f, 38).rejected.getOrElse("unsigned", 0L) should be > 0L
        }
      }
    }

    "not discover an unknown robot from unsigned keep-alives while a team key is set, but from signed ones" in {
      val ip = TestLoopback.address()
      withGateway(39, ip) { f =>
        f.robot(40) // unsigned, not configured
        f.robot(41, firmware = signing) // signed, not configured
        eventually(timeout(10.seconds)) {
          snapshot(f, 41).online shouldBe true
          f.stats().rejected.getOrElse("unsigned", 0L) should be > 0L
        }
        val probe = createTestProbe[Option[akka.actor.typed.ActorRef[RobotAccess.Command]]]()
        f.gateway ! GatewayAccess.GetRobotAccess(40, probe.ref)
        probe.receiveMessage(5.seconds) shouldBe None
      }
    }
  }

  private def collect(f: GatewayFixture, window: FiniteDuration): Vector[GatewayEvent] = {
    val deadline = window.fromNow
    var events = Vector.empty[GatewayEvent]
    while (deadline.hasTimeLeft()) {
      try events :+= f.events.receiveMessage(deadline.timeLeft.max(1.milli))
      catch { case _: AssertionError => () }
    }
    events
  }
}

object SignedFramesSpec {

  /** The team key of the tests (the key of protocol.md 9.14). */
  val TeamKeyHex: String = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f"
  val TeamKey: SigningKey = SigningKey.fromHex(TeamKeyHex).toOption.get
  val WrongKey: SigningKey = SigningKey.fromHex("ff" + TeamKeyHex.drop(2)).toOption.get

  val SignatureKinds: Set[String] =
    Set("unsigned", "signature not last", "malformed signature", "bad signature", "replayed")

}
