package naogateway.launcher

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.concurrent.Eventually
import org.scalatest.wordspec.AnyWordSpecLike

import apps.control.{ControlServer, ControlSettings}
import apps.zeromq.PythonClientSpec
import naogateway.gateway.{Gateway, GatewaySettings, ZeroMqRobot}
import robotmiddleware.{MiddlewareSettings, RobotMiddleware}

/** robotctl against a real gateway and the simulated firmware: every error a robot answers (protocol.md §7.4) ends the
  * control exchange with `error …` and robotctl with exit code 1, whatever the error's kind.
  */
class RobotCtlRobotErrorSpec
    extends ScalaTestWithActorTestKit(PythonClientSpec.config + "\napps.zeromq.enabled = off\n")
    with AnyWordSpecLike
    with LogCapturing
    with Eventually {

  private final case class Run(code: Int, out: Vector[String], err: Vector[String])

  private def robotctl(control: String, args: String*): Run = {
    val out = Vector.newBuilder[String]
    val err = Vector.newBuilder[String]
    val code = RobotCtl.run("--control" +: control +: args, _ => None, out += _, err += _)
    Run(code, out.result(), err.result())
  }

  "robotctl" should {
    "exit 1 with the robot's error text for every kind of robot error, 0 for a value" in {
      val robot = PythonClientSpec.startRobot()
      try {
        val configured = GatewaySettings(system)
        val gateway = spawn(Gateway(configured.copy(zeromq = configured.zeromq.copy(robots = Vector(ZeroMqRobot(20,
                robot.endpoint))))),
          "gateway")
        val middleware = spawn(RobotMiddleware(gateway, MiddlewareSettings(system)), "middleware")
        val server =
          spawn(ControlServer(middleware, ControlSettings(system).copy(host = "127.0.0.1", port = 0)), "control")
        val probe = createTestProbe[InetSocketAddress]()
        server ! ControlServer.GetAddress(probe.ref)
        val control = s"127.0.0.1:${probe.receiveMessage(10.seconds).getPort}"

        eventually(timeout(20.seconds), interval(200.millis)) {
          robotctl(control, "call", "20", "system", "ping").code shouldBe 0
        }
        // One call per error kind of §7.4 the simulated firmware can give from its starting posture (sit).
        val errors = Vector(
          Seq("call", "20", "motion", "head", "0.0", "0.8") -> "out of range: ",
          Seq("call", "20", "motion", "dance") -> "unknown method: motion.dance",
          Seq("call", "20", "motion", "walk", "0.1", "0.0") -> "bad parameters: ",
          Seq("call", "20", "motion", "walk", "0.1", "0.0", "0.0") -> "not standing: sit"
        )
        errors.foreach { case (args, text) =>
          val run = robotctl(control, args: _*)
          withClue(s"robotctl ${args.mkString(" ")}: $run") {
            run.code shouldBe RobotCtl.ExitFailed
            run.out shouldBe empty
            run.err should have size 1
            run.err.head should startWith(s"robotctl: robot 20: $text")
          }
        }
        val head = robotctl(control, "call", "20", "motion", "head", "0.5", "0.2")
        head shouldBe Run(RobotCtl.ExitOk, Vector("robot 20: motion.head -> Flag(true)"), Vector.empty)
      } finally robot.stop()
    }
  }
}
