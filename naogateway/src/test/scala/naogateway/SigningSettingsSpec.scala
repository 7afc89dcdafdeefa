package naogateway

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
    "read the key and each robot's setting, off by default, and never show the key" in {
      val s = settings(s"""signing.key = "$hex"
        |robots = [ { id = 1, address = "10.0.0.1", signing = required }, { id = 2, address = "10.0.0.2" } ]""".stripMargin)
      s.signingKey shouldBe Some(teamKey)
      s.signingOf(1) shouldBe RobotSigning.Required
      s.signingOf(2) shouldBe RobotSigning.Off
      s.signingOf(99) shouldBe RobotSigning.Off
      s.toString should not include hex
      s.toString should not include hex.toUpperCase
      settings("").signingKey shouldBe None
    }
    "refuse a bad key, naming the key but never its digits" in {
      val odd = refusal("""signing.key = "0001020"""")
      odd should include("signing.key")
      odd should not include "0001020"
      val short = refusal("""signing.key = "00010203"""")
      short should include("at least 16 bytes")
      short should not include "00010203"
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

  "The gateway's signer" should {
    "sign with ever-growing timestamps, even when the clock goes back, frames the robot can check" in {
      var clock = 1000L
      val signer = new FrameSigner(teamKey, () => clock)
      val frame = MessageContents.encodeFrame(MessageContents(1,
          debuggingCommands = Some(naogateway.proto.DebuggingCommands(optionPull = Some(true)))))
        .toOption.get
      val stamps = (1 to 5).map { i =>
        clock = if (i == 3) 10L else clock + 1
        val signed = signer.sign(frame).toOption.get
        val header = FumanoidsFrame.decodeHeader(signed).toOption.get
        FrameSigning.verifyFrame(signed, header, teamKey, SignDirection.GatewayToRobot).toOption.get.timestamp
      }
      stamps.sliding(2).foreach(pair => pair(1) should be > pair(0))
      stamps.head shouldBe 1001L
    }
  }

  "A robot's signature check" should {
    "accept each signed frame once, in growing order, and name the kind of every refusal" in {
      val check = new SignatureCheck(teamKey)
      val contents = MessageContents(3, status = Some(naogateway.proto.Status(teamID = Some(1))))
      def frame(ts: Long, k: SigningKey = teamKey) =
        FrameSigning.signFrame(contents, HeaderForm.Compact, k, SignDirection.RobotToGateway, ts).toOption.get
      def run(bytes: Array[Byte]) = check.check(bytes, FumanoidsFrame.decodeHeader(bytes).toOption.get)
      run(frame(10)) shouldBe Right(())
      run(frame(10)) shouldBe Left(Rejection.Replayed)
      run(frame(9)) shouldBe Left(Rejection.Replayed)
      run(frame(11, SigningKey.fromHex("ff" + hex.drop(2)).toOption.get)) shouldBe Left(Rejection.BadSignature)
      run(MessageContents.encodeFrame(contents).toOption.get) shouldBe Left(Rejection.Unsigned)
      // Signed for the gateway's direction: a robot's own frames cannot be reflected to it, nor the gateway's to it.
      run(FrameSigning.signFrame(contents, HeaderForm.Compact, teamKey, SignDirection.GatewayToRobot, 12).toOption.get) shouldBe
        Left(Rejection.BadSignature)
      run(frame(12)) shouldBe Right(())
      check.lastAccepted shouldBe Some(12L)
    }
  }
}
