package apps.control

import com.typesafe.config.ConfigFactory
import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import apps.control.ControlProtocol.{Answer, Request}
import naogateway.wire.RpcValue

class ControlProtocolSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {

  implicit override val generatorDrivenConfig: PropertyCheckConfiguration =
    PropertyCheckConfiguration(minSuccessful = 500)

  // Any string, lone surrogates and control characters included, and now and then a long one.
  private val anyText: Gen[String] = Gen.frequency(
    10 -> Gen.asciiStr,
    10 -> Gen.stringOf(Gen.oneOf(Gen.choose(Char.MinValue, Char.MaxValue),
        Gen.oneOf(' ', '\\', '\n', '\r', '\t', 'u', 's'))),
    1 -> Gen.choose(1000, 3000).flatMap(n => Gen.listOfN(n, Gen.alphaNumChar).map(_.mkString))
  )

  private val anyParam: Gen[RpcValue] = Gen.oneOf(
    Gen.choose(-1e30f, 1e30f).map(RpcValue.Number(_)),
    Gen.oneOf(Float.MinPositiveValue, Float.MaxValue, Float.PositiveInfinity, Float.NegativeInfinity, -0.0f).map(
      RpcValue.Number(_)),
    Gen.oneOf(true, false).map(RpcValue.Flag(_)),
    anyText.map(RpcValue.Text(_))
  )

  private val anyRequest: Gen[Request] = Gen.oneOf(
    Gen.const(Request.Status),
    for { id <- Gen.choose(Int.MinValue, Int.MaxValue); s <- Gen.choose(1, Int.MaxValue) } yield Request.Watch(id, s),
    Gen.choose(Int.MinValue, Int.MaxValue).map(Request.Servos(_)),
    for {
      id <- Gen.choose(Int.MinValue, Int.MaxValue)
      module <- anyText
      method <- anyText
      params <- Gen.listOf(anyParam).map(_.take(6).toVector)
    } yield Request.Call(id, module, method, params)
  )

  private val anyAnswer: Gen[Answer] = anyText.flatMap(t => Gen.oneOf(Answer.Line(t), Answer.Ok(t), Answer.Error(t)))

  "A request line" should {
    "read back as the request it renders, or be refused as too long, and never hold a raw line break" in {
      forAll(anyRequest) { request =>
        val line = ControlProtocol.render(request)
        line.exists(c => c == '\n' || c == '\r') shouldBe false
        if (ControlProtocol.utf8Length(line) <= ControlProtocol.MaxRequestBytes)
          ControlProtocol.readRequest(line) shouldBe Right(request)
        else ControlProtocol.readRequest(line) shouldBe Left(
          s"request line longer than ${ControlProtocol.MaxRequestBytes} bytes")
      }
    }

    "be read or refused with a message, whatever it holds" in {
      val words =
        Gen.oneOf(Gen.oneOf("status", "call", "watch", "1", "n:1.0", "t:a\\sb", "f:true", "\\", "\\u12", ""), anyText)
      forAll(Gen.oneOf(anyText, Gen.listOf(words).map(_.mkString(" ")))) { line =>
        ControlProtocol.readRequest(line) match {
          case Right(request) => ControlProtocol.readRequest(ControlProtocol.render(request)) shouldBe Right(request)
          case Left(message)  => message should not be empty
        }
      }
    }

    "refuse overlong lines, broken escapes and bad words with a clear message" in {
      ControlProtocol.readRequest("call 1 m f t:" + "x" * 5000) shouldBe Left("request line longer than 4096 bytes")
      ControlProtocol.readRequest("dance") shouldBe Left("unknown request 'dance'")
      ControlProtocol.readRequest("call x motion getPosture") shouldBe Left("robot id 'x' is not a number")
      ControlProtocol.readRequest("call 1 motion getPosture t:\\q") shouldBe Left("unknown escape \\q")
      ControlProtocol.readRequest("call 1 motion getPosture n:0x10") shouldBe Left("'n:0x10' is not a number parameter")
      ControlProtocol.readRequest("call 1 motion getPosture 3") shouldBe Left("parameter '3' is not n:, f: or t:")
      ControlProtocol.readRequest("watch 1 0") shouldBe Left("'0' is not a number of seconds")
      ControlProtocol.readRequest("call 1 motion posture t:dance") shouldBe Left(
        "unknown posture 'dance' (sit, stand, crouch)")
      ControlProtocol.readRequest("call 1 motion posture t:walking") shouldBe Left(
        "unknown posture 'walking' (sit, stand, crouch)")
      ControlProtocol.readRequest("call 1 motion posture t:crouch") shouldBe
        Right(Request.Call(1, "motion", "posture", Vector(RpcValue.Text("crouch"))))
      ControlProtocol.readRequest("status\r") shouldBe Right(Request.Status)
    }

    "keep spaces, backslashes and empty words of the command line" in {
      val request = Request.Call(2, "speech", "",
        Vector(RpcValue.Text("hello world \\s"), RpcValue.Text(""), RpcValue.Number(0.5f)))
      ControlProtocol.render(request) shouldBe "call 2 speech  t:hello\\sworld\\s\\\\s t: n:0.5"
      ControlProtocol.readRequest(ControlProtocol.render(request)) shouldBe Right(request)
    }
  }

  "An answer line" should {
    "read back as the answer it renders when it fits a line" in {
      forAll(anyAnswer) { answer =>
        val line = ControlProtocol.render(answer)
        line.exists(c => c == '\n' || c == '\r') shouldBe false
        if (ControlProtocol.utf8Length(line) <= ControlProtocol.MaxAnswerBytes)
          ControlProtocol.readAnswer(line) shouldBe Right(answer)
        else ControlProtocol.readAnswer(line).isLeft shouldBe true
      }
    }

    "be read or refused with a message, whatever it holds" in {
      forAll(Gen.oneOf(anyText, anyText.map(". " + _), anyText.map("error " + _))) { line =>
        ControlProtocol.readAnswer(line) match {
          case Right(answer) => ControlProtocol.readAnswer(ControlProtocol.render(answer)) shouldBe Right(answer)
          case Left(message) => message should not be empty
        }
      }
    }

    "come out of any output text as lines that each fit, and give the text back" in {
      forAll(Gen.oneOf(anyText,
          Gen.choose(5000, 30000).flatMap(n =>
            Gen.listOfN(n, Gen.oneOf('a', '\u0001', '\ud83d', '\ude00')).map(_.mkString)))) {
        text =>
          val lines = ControlProtocol.lines(text)
          lines.foreach(l =>
            ControlProtocol.utf8Length(ControlProtocol.render(l)) should be <= ControlProtocol.MaxAnswerBytes)
          lines.map(_.text).mkString shouldBe text.replaceAll("\r?\n", "")
      }
    }
  }

  "The command line" should {
    "parse into requests, with the usage when it is not a command" in {
      ControlProtocol.parse(Seq("status")) shouldBe Right(Request.Status)
      ControlProtocol.parse(Seq("watch", "3", "5", "6")) shouldBe Left(ControlProtocol.usage)
      ControlProtocol.parse(Seq("call", "2", "motion")) shouldBe Left(ControlProtocol.usage)
      // The demo's battery swap travels as one line and reads back as it was.
      ControlProtocol.parse(Seq("battery", "2", "swap")) shouldBe Right(Request.BatterySwap(2))
      ControlProtocol.render(Request.BatterySwap(2)) shouldBe "battery 2 swap"
      ControlProtocol.readRequest("battery 2 swap") shouldBe Right(Request.BatterySwap(2))
      ControlProtocol.parse(Seq("battery", "2")) shouldBe Left(ControlProtocol.usage)
      ControlProtocol.parse(Seq("battery", "x", "swap")) shouldBe Left("robot id 'x' is not a number")
    }
  }

  "A servo table" should {
    "show each servo's figures, silent, hot, low-voltage and error marks, and say when there is none" in {
      val at = 5000000000L
      val robot = naogateway.api.RobotSnapshot(
        2,
        new java.net.InetSocketAddress("127.0.0.1", 3838),
        online = true,
        servos = Some(naogateway.api.ServoReadings(
            Vector(
              naogateway.api.ServoReading(1, Some(512), Some(-40), Some(12.1), Some(41)),
              naogateway.api.ServoReading(2, Some(614), Some(300), Some(9.8), Some(66), error = 32),
              naogateway.api.ServoReading(3, silent = true)
            ),
            Some(4L),
            at - 250000000L
          ))
      )
      val lines = ControlText.servoLines(robot, robotmiddleware.ServoLimits(65, 10.0), at)
      lines.head shouldBe "robot 2: 3 servos, read 250 ms ago, 4 bus errors since power-up"
      lines(2) should (startWith("1 ") and include("512 (+0°)") and include("-40") and include("12.1 V") and
        include("41 °C"))
      lines(2) should not include "HOT"
      lines(3) should (include("614 (+30°)") and include("HOT, LOW VOLTAGE, error 0x20"))
      lines(4) shouldBe "3    silent"
      ControlText.servoLines(robot.copy(servos = None), robotmiddleware.ServoLimits(), at) shouldBe List(
        "robot 2: no servo telemetry yet")
      ControlProtocol.parse(Seq("servos", "2")) shouldBe Right(Request.Servos(2))
    }
  }

  "An address" should {
    "be host:port, with brackets for IPv6 literals" in {
      ControlProtocol.address("127.0.0.1:11019") shouldBe Right("127.0.0.1" -> 11019)
      ControlProtocol.address("[::1]:7") shouldBe Right("::1" -> 7)
      ControlProtocol.address("localhost") shouldBe Left("'localhost' is not host:port")
      ControlProtocol.address(":80") shouldBe Left("':80' is not host:port")
      ControlProtocol.address("h:99999") shouldBe Left("'h:99999' is not host:port")
    }

    "default to where the gateway binds by default" in {
      assume(sys.env.get(ControlProtocol.AddressVariable).isEmpty, "NAOGATEWAY_CONTROL overrides the default here")
      val settings = ControlSettings.fromConfig(ConfigFactory.defaultReference().getConfig(ControlSettings.ConfigPath))
      s"${settings.host}:${settings.port}" shouldBe ControlProtocol.DefaultAddress
      settings.enabled shouldBe true
    }
  }
}
