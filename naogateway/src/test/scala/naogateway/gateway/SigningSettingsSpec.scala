package naogateway.gateway

import com.typesafe.config.ConfigFactory
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.testkit.SettingsTables
import naogateway.wire._

class SigningSettingsSpec extends AnyWordSpec with Matchers with SettingsTables {

  private val hex = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f"
  private val teamKey = SigningKey.fromHex(hex).toOption.get

  private def settings(overrides: String): GatewaySettings =
    overriding("naogateway", ConfigFactory.defaultReference())(GatewaySettings.fromConfig)(overrides)

  private def refusal(overrides: String): String = messageOf(settings)(overrides)

  "The signing settings" should {
    "read the key; with it every robot signs unless its entry says off; never show the key" in {
      val s = settings(s"""signing.key = "$hex"
        |robots = [ { id = 1, address = "10.0.0.1", signing = required }, { id = 2, address = "10.0.0.2" },
        |  { id = 3, address = "10.0.0.3", signing = off } ]""".stripMargin)
      s.signingKey shouldBe Some(teamKey)
      s.signingOf(1) shouldBe RobotSigning.Required
      s.signingOf(2) shouldBe RobotSigning.Required
      s.signingOf(3) shouldBe RobotSigning.Off
      // A robot not configured (a discovered one) must sign too while there is a team key.
      s.signingOf(99) shouldBe RobotSigning.Required
      s.toString should not include hex
      s.toString should not include hex.toUpperCase
      val keyless = settings("""robots = [ { id = 2, address = "10.0.0.2" } ]""")
      keyless.signingKey shouldBe None
      keyless.signingOf(2) shouldBe RobotSigning.Off
      keyless.signingOf(99) shouldBe RobotSigning.Off
    }
    "refuse a bad key, naming the key but never its digits" in {
      val odd = refusal("""signing.key = "0001020"""")
      odd should include("signing.key")
      odd should not include "0001020"
      val short = refusal("""signing.key = "00010203"""")
      short should include("at least 16 bytes")
      short should not include "00010203"
      val long = refusal(s"""signing.key = "${"ab" * 65}"""")
      long should include("at most 64 bytes")
      long should not include "abab"
      refusal("""signing.key = "zz0102030405060708090a0b0c0d0e0f"""") should include("hexadecimal")
    }
    "refuse a robot that must sign when there is no key, and a setting other than off or required" in {
      refusal("""robots = [ { id = 4, address = "10.0.0.4", signing = required } ]""") should
        (include("robot 4") and include("NAOGATEWAY_SIGNING_KEY"))
      refusal(s"""signing.key = "$hex"
        |robots = [ { id = 5, address = "10.0.0.5", signing = maybe } ]""".stripMargin) should include(
        "off or required")
    }
  }

  private val optionPull = MessageContents.encodeFrame(MessageContents(1,
      debuggingCommands = Some(naogateway.proto.DebuggingCommands(optionPull = Some(true))))).toOption.get
  private val keepAlive = MessageContents(1, status = Some(naogateway.proto.Status(teamID = Some(1))))

  private def robotFrame(robotId: Int, ts: Long, k: SigningKey = teamKey, contents: MessageContents = keepAlive) =
    FrameSigning.signFrame(contents.copy(robotId = robotId), HeaderForm.Compact, k.robotKey(robotId),
      SignedLink.FromRobot(robotId), ts).toOption.get

  private def header(bytes: Array[Byte]) = FumanoidsFrame.decodeHeader(bytes).toOption.get

  "The gateway's signer" should {
    "sign nothing for a robot before its boot epoch is known: the frame is refused, never left unsigned" in {
      val signing = new GatewaySigning(teamKey, () => 1000L)
      signing.robot(1)
      signing.canSign(1) shouldBe false
      signing.sign(1, optionPull) shouldBe Left(SignRefusal.EpochUnknown(1))
      signing.sign(2, optionPull) shouldBe Left(SignRefusal.EpochUnknown(2))
      signing.refusals shouldBe 2L
    }
    "sign with ever-growing timestamps, even when the clock goes back, under the robot's key and current epoch" in {
      var clock = 1000L
      val signing = new GatewaySigning(teamKey, () => clock)
      signing.robot(1).check(robotFrame(1, FrameSigning.robotTimestamp(4, 0)),
        header(robotFrame(1, FrameSigning.robotTimestamp(4, 0)))) shouldBe Right(())
      signing.epochOf(1) shouldBe Some(4)
      val stamps = (1 to 5).map { i =>
        clock = if (i == 3) 10L else clock + 1
        val signed = signing.sign(1, optionPull).toOption.get
        FrameSigning.verifyFrame(signed, header(signed), teamKey.robotKey(1), SignedLink.ToRobot(1, 4))
          .toOption.get.timestamp
      }
      stamps.sliding(2).foreach(pair => pair(1) should be > pair(0))
      stamps.head shouldBe 1001L
      // After the robot's reboot (epoch 5), frames carry the new epoch: those of epoch 4 no longer verify there.
      val rebooted = robotFrame(1, FrameSigning.robotTimestamp(5, 0))
      signing.robot(1).check(rebooted, header(rebooted)) shouldBe Right(())
      val next = signing.sign(1, optionPull).toOption.get
      FrameSigning.verifyFrame(next, header(next), teamKey.robotKey(1), SignedLink.ToRobot(1, 5)).isRight shouldBe true
      FrameSigning.verifyFrame(next, header(next), teamKey.robotKey(1), SignedLink.ToRobot(1, 4)) shouldBe
        Left(SignatureError.BadMac)
    }
    "keep a check for an unknown robot id only when its frame verifies" in {
      val signing = new GatewaySigning(teamKey)
      val forged = robotFrame(9, 7L, SigningKey.fromHex("ff" + hex.drop(2)).toOption.get)
      signing.checkNew(9, forged, header(forged)).left.toOption shouldBe Some(Rejection.BadSignature)
      signing.epochOf(9) shouldBe None
      val real = robotFrame(9, FrameSigning.robotTimestamp(2, 0))
      signing.checkNew(9, real, header(real)).map(_.robotId) shouldBe Right(9)
      signing.epochOf(9) shouldBe Some(2)
      signing.checkNew(9, real, header(real)).left.toOption shouldBe Some(Rejection.Replayed)
    }
  }

  "A robot's signature check" should {
    "accept each signed frame once, in growing order, and name the kind of every refusal" in {
      val check = new GatewaySigning(teamKey).robot(3)
      def frame(ts: Long, k: SigningKey = teamKey) = robotFrame(3, ts, k)
      def run(bytes: Array[Byte]) = check.check(bytes, header(bytes))
      run(frame(10)) shouldBe Right(())
      run(frame(10)) shouldBe Left(Rejection.Replayed)
      run(frame(9)) shouldBe Left(Rejection.Replayed)
      run(frame(11, SigningKey.fromHex("ff" + hex.drop(2)).toOption.get)) shouldBe Left(Rejection.BadSignature)
      run(MessageContents.encodeFrame(keepAlive.copy(robotId = 3)).toOption.get) shouldBe Left(Rejection.Unsigned)
      // Signed for the gateway's direction: a robot's own frames cannot be reflected to it, nor the gateway's to it.
      run(FrameSigning.signFrame(keepAlive.copy(robotId = 3), HeaderForm.Compact, teamKey.robotKey(3),
          SignedLink.ToRobot(3, 0), 12).toOption.get) shouldBe Left(Rejection.BadSignature)
      run(frame(12)) shouldBe Right(())
      check.lastAccepted shouldBe Some(12L)
    }
    "refuse a frame robot A signed when it comes as robot B's, and accept a reboot's higher epoch" in {
      val signing = new GatewaySigning(teamKey)
      val b = signing.robot(2)
      // Robot 1's frame, signed by robot 1: as robot 2's (its id rewritten, or as it is) it fails robot 2's check.
      val fromA = robotFrame(1, FrameSigning.robotTimestamp(3, 9))
      b.check(fromA, header(fromA)) shouldBe Left(Rejection.BadSignature)
      val aKeyAsB = FrameSigning.signFrame(keepAlive.copy(robotId = 2), HeaderForm.Compact, teamKey.robotKey(1),
        SignedLink.FromRobot(2), FrameSigning.robotTimestamp(3, 9)).toOption.get
      b.check(aKeyAsB, header(aKeyAsB)) shouldBe Left(Rejection.BadSignature)
      val aLinkAsB = FrameSigning.signFrame(keepAlive.copy(robotId = 2), HeaderForm.Compact, teamKey.robotKey(2),
        SignedLink.FromRobot(1), FrameSigning.robotTimestamp(3, 9)).toOption.get
      b.check(aLinkAsB, header(aLinkAsB)) shouldBe Left(Rejection.BadSignature)
      val late = robotFrame(2, FrameSigning.robotTimestamp(3, 1000))
      b.check(late, header(late)) shouldBe Right(())
      val rebooted = robotFrame(2, FrameSigning.robotTimestamp(4, 0))
      b.check(rebooted, header(rebooted)) shouldBe Right(())
      b.epoch shouldBe Some(4)
    }
  }
}
