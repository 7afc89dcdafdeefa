package naogateway.launcher

import java.net.{InetAddress, ServerSocket}
import java.nio.charset.StandardCharsets

import scala.concurrent.duration._
import scala.concurrent.{Await, ExecutionContext, Future}

import ch.qos.logback.classic.spi.LoggingEvent
import ch.qos.logback.classic.{Level, LoggerContext}
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import apps.control.ControlProtocol
import apps.control.ControlProtocol.Answer
import naogateway.api.Printable

/** A robot's role carrying a terminal escape sequence, as a stranger posing as the robot would send it, reaches
  * robotctl's output and the launcher's log with its control characters replaced.
  */
class RobotCtlPrintableSpec extends AnyWordSpec with Matchers {

  /** What a forged keep-alive puts in the role: clear the screen, retitle the window, an 8-bit CSI, a fake log line. */
  private val hostileRole = "keeper\u001b[2J\u001b]0;owned\u0007\u009b31m\nINFO all is well"

  private def controlChars(s: String): Boolean = s.exists(Printable.control)

  "robotctl" should {
    "print a robot's role with an escape sequence in it without one raw control character" in {
      // A control port that answers every request with a status line holding the role, as the gateway would.
      val server = new ServerSocket(0, 1, InetAddress.getLoopbackAddress)
      val answered = Future {
        val socket = server.accept()
        try {
          val in = socket.getInputStream
          while (in.read() != '\n') ()
          val lines = Seq(Answer.Line(s"robot 1   online  good     role $hostileRole"), Answer.Ok(s"done $hostileRole"))
          socket.getOutputStream.write(lines.map(ControlProtocol.render(_) + "\n").mkString.getBytes(
              StandardCharsets.UTF_8))
          socket.getOutputStream.flush()
        } finally socket.close()
      }(ExecutionContext.global)
      try {
        val out = Vector.newBuilder[String]
        val err = Vector.newBuilder[String]
        val code = RobotCtl.run(Seq("--control", s"127.0.0.1:${server.getLocalPort}", "status"), _ => None,
          out += _, err += _)
        Await.result(answered, 10.seconds)
        code shouldBe RobotCtl.ExitOk
        val printed = out.result()
        printed should have size 2
        printed.exists(controlChars) shouldBe false
        printed.head should include("role keeper\\u001b[2J\\u001b]0;owned\\u0007\\u009b31m\\u000aINFO all is well")
        err.result() shouldBe empty
      } finally server.close()
    }
  }

  "The launcher's log" should {
    "write a message holding a robot's role with its control characters replaced" in {
      val event = new LoggingEvent("apps.Test", new LoggerContext().getLogger("apps.Test"), Level.WARN,
        "robot {} reports role {}", null, Array[AnyRef](Integer.valueOf(1), hostileRole))
      val line = new PrintableMessage().convert(event)
      controlChars(line) shouldBe false
      line shouldBe s"robot 1 reports role ${Printable.text(hostileRole)}"
      // The launcher's logback.xml writes messages through it.
      val xml = scala.io.Source.fromResource("logback.xml").mkString
      xml should include("converterClass=\"naogateway.launcher.PrintableMessage\"")
      xml should include("%safemsg")
      xml should not include "%msg"
    }
  }
}
