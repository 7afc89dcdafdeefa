package naogateway.integration

import java.net.{InetAddress, InetSocketAddress}
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._
import scala.util.Random

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway._
import naogateway.sim.network.ForgedFrames
import naogateway.testkit.TestLoopback
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

  /** A gateway requiring robot `robotId` at `ip` to sign, relaying every robot datagram to `relayPort` (a recorder). */
  private def withGateway[A](robotId: Int, ip: InetAddress, relayPort: Int = 0)(test: GatewayFixture => A): A = {
    val relay =
      if (relayPort == 0) "" else s"fu-remote-relay { enabled = on, address = \"127.0.0.1\", port = $relayPort }"
    val f = new GatewayFixture(
      testKit,
      s"""robots = [ { id = $robotId, address = "${ip.getHostAddress}", signing = required } ]
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
    "answer a signed robot's calls, take its keep-alives, and sign what it sends; an unsigned robot beside it works as before" in {
      val ip = TestLoopback.address()
      withGateway(31, ip) { f =>
        val (robot, _) = f.robot(31, firmware = signing, at = ip)
        val (plain, _) = f.robot(32)
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
            outsider.send(ByteBuffer.wrap(FrameSigning.signFrame(stand, HeaderForm.Legacy, WrongKey,
                  SignDirection.GatewayToRobot,
                  Long.MaxValue - i).toOption.get), receivesAt)
          }
          eventually(timeout(10.seconds)) {
            f.view(robot).firmware.refusedSignatures shouldBe Map("unsigned" -> 5L, "bad signature" -> 5L)
          }
          f.view(robot).posture shouldBe Posture.Sit
        } finally outsider.close()
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
