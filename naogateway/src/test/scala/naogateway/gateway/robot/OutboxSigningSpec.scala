package naogateway.gateway.robot

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.api.Priority
import naogateway.gateway.{BudgetSettings, GatewaySigning}
import naogateway.gateway.link.UdpLink
import naogateway.proto.DebuggingCommands
import naogateway.wire._

class OutboxSigningSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {
  private val robot = new InetSocketAddress("127.0.0.1", 3838)
  private val teamKey =
    SigningKey.fromHex("000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f").toOption.get

  private def writer(link: akka.actor.typed.ActorRef[UdpLink.Command]): naogateway.transport.DatagramWriter =
    (bytes, to) => {
      link ! UdpLink.Send(bytes, to)
      true
    }

  /** An unsigned frame to robot 1: an option pull, or a `say` call carrying `padding` characters. */
  private def frame(padding: Int): Array[Byte] = {
    val contents =
      if (padding == 0) MessageContents(1, debuggingCommands = Some(DebuggingCommands(optionPull = Some(true))))
      else MessageContents(1,
        rpcRequest = Some(RpcCall("speech", "say", Vector(RpcValue.Text("x" * padding)), Some(1L)).toProto))
    MessageContents.encodeFrame(contents).toOption.get
  }

  private def timestampOf(bytes: Array[Byte]): Long = {
    val header = FumanoidsFrame.decodeHeader(bytes).toOption.get
    FrameSigning.verifyFrame(bytes, header, teamKey.robotKey(1), SignedLink.ToRobot(1, 6)).toOption.get.timestamp
  }

  /** The gateway's signing after robot 1's keep-alive of boot epoch 6 was accepted (robot 2's epoch is unknown). */
  private def gatewaySigning(): GatewaySigning = {
    val g = new GatewaySigning(teamKey)
    val keepAlive = FrameSigning.signFrame(MessageContents(1), HeaderForm.Legacy, teamKey.robotKey(1),
      SignedLink.FromRobot(1), FrameSigning.robotTimestamp(6, 0)).toOption.get
    g.robot(1).check(keepAlive, FumanoidsFrame.decodeHeader(keepAlive).toOption.get) shouldBe Right(())
    g
  }

  "An outbox with a signer" must {
    "sign frames as they leave, so timestamps grow in the order the robot gets them, whatever the queues reorder" in {
      val link = createTestProbe[UdpLink.Command]()
      val outbox = spawn(Outbox(writer(link.ref), BudgetSettings(1400, 0, 0.8), competition = false,
          Some(gatewaySigning())))
      val outcomes = createTestProbe[Outbox.Outcome]()
      val big = frame(padding = 1300)
      // The first takes nearly the whole second of the budget; the debug frame waits; the safety frames overtake it.
      outbox ! Outbox.Send(1, robot, big, Priority.Command, Some(outcomes.ref), 1L, signed = true)
      outbox ! Outbox.Send(1, robot, frame(0), Priority.Debug, Some(outcomes.ref), 2L, signed = true)
      outbox ! Outbox.Send(1, robot, frame(0), Priority.Safety, Some(outcomes.ref), 3L, signed = true)
      outbox ! Outbox.Send(1, robot, Array[Byte](3, 5, 1, 2), Priority.Safety, Some(outcomes.ref), 4L)
      val sent = (1 to 4).map(_ => link.expectMessageType[UdpLink.Send](5.seconds).bytes)
      // A stream segment is never signed.
      sent(2).toVector shouldBe Vector[Byte](3, 5, 1, 2)
      val frames = Vector(sent(0), sent(1), sent(3))
      frames.map(_.length) shouldBe Vector(big.length, frame(0).length, frame(0).length).map(
        _ + FrameSigning.FieldBytes)
      // Queued before the safety frame, sent after it: signed after it too, so the robot takes both.
      val stamps = frames.map(timestampOf)
      stamps.sliding(2).foreach(pair => pair(1) should be > pair(0))
    }
    "drop a frame that would exceed 1400 bytes with its signature, one it has no key for, and one to a robot whose epoch it does not know" in {
      val link = createTestProbe[UdpLink.Command]()
      val outcomes = createTestProbe[Outbox.Outcome]()
      val signing = spawn(Outbox(writer(link.ref), BudgetSettings(125000, 0, 0.8), competition = false,
          Some(gatewaySigning())))
      val tooBig = frame(padding = 1400 - FrameSigning.FieldBytes - 20)
      tooBig.length should (be <= WireLimits.MaxDatagramBytes and be > WireLimits.MaxDatagramBytes - FrameSigning.FieldBytes)
      signing ! Outbox.Send(1, robot, tooBig, Priority.Command, Some(outcomes.ref), 7L, signed = true)
      outcomes.expectMessageType[Outbox.Dropped].tag shouldBe 7L
      signing ! Outbox.Send(2, robot, frame(0), Priority.Command, Some(outcomes.ref), 9L, signed = true)
      outcomes.expectMessageType[Outbox.Dropped].reason should include("boot epoch is not known")
      val keyless = spawn(Outbox(writer(link.ref), BudgetSettings(125000, 0, 0.8), competition = false))
      keyless ! Outbox.Send(1, robot, frame(0), Priority.Command, Some(outcomes.ref), 8L, signed = true)
      outcomes.expectMessageType[Outbox.Dropped].tag shouldBe 8L
      link.expectNoMessage(200.millis)
    }
  }
}
