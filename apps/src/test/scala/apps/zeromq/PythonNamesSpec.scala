package apps.zeromq

import java.io.File
import java.nio.charset.StandardCharsets
import java.nio.file.Files

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.wire.{ActuatorGroup, Posture, RpcMethod}

/** The Python client's names for postures, actuator groups and robot methods are the gateway's, in the same order. */
class PythonNamesSpec extends AnyWordSpec with Matchers {

  private lazy val client: String =
    new String(Files.readAllBytes(new File(PythonEnv.root, "apps/python/naogateway_client/__init__.py").toPath),
      StandardCharsets.UTF_8)

  /** The strings of the module-level tuple `name = ("a", "b", ...)` in the client's source. */
  private def tuple(name: String): Vector[String] = {
    val assignment = s"""(?m)^$name = \\(([^)]*)\\)""".r
    val body = assignment.findFirstMatchIn(client).getOrElse(
      fail(s"apps/python/naogateway_client/__init__.py has no $name tuple")).group(1)
    "\"([^\"]*)\"".r.findAllMatchIn(body).map(_.group(1)).toVector
  }

  "The Python client" should {
    "name every posture a robot reports as Posture does" in {
      tuple("POSTURES") shouldBe Posture.known.map(_.name)
    }

    "name the postures a caller may ask for as Posture.targets does" in {
      tuple("POSTURE_TARGETS") shouldBe Posture.targets.map(_.name)
    }

    "name the actuator groups as ActuatorGroup does" in {
      tuple("ACTUATOR_GROUPS") shouldBe ActuatorGroup.all.map(_.name)
    }

    "call only robot methods of RpcMethod, each by its module and method name" in {
      // Every `self.call(robot_id, "module", "method", ...)` except the endpoint's own module `gateway`.
      val Call = """self\.call\(robot_id, "([a-zA-Z]+)", "([a-zA-Z]+)"""".r
      val called = Call.findAllMatchIn(client).map(m => (m.group(1), m.group(2))).filterNot(_._1 == "gateway").toVector
      called should not be empty
      all(called.map { case (module, method) => RpcMethod.find(module, method).map(_.name) }) shouldBe defined
      // The client's named commands: motion.walk, stop, head, arms, posture and speech.say at least.
      called.map { case (m, n) => s"$m.$n" }.toSet should contain allElementsOf
        Set(RpcMethod.Walk, RpcMethod.Stop, RpcMethod.Head, RpcMethod.Arms, RpcMethod.Posture, RpcMethod.Say).map(
          _.name)
    }
  }
}
