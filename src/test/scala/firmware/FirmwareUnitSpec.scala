package firmware

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** The C library's own unit tests (`make -C firmware test`: windows 1 and 4, and 4 with a queue) as part of `./sbt
  * test`: they pass when make succeeds and its summary line counts no failure. Cancelled with the reason when a tool is
  * missing.
  */
class FirmwareUnitSpec extends AnyWordSpec with Matchers {
  private val Summary = """(?m)^(\d+) passed, (\d+) failed$""".r

  "The firmware's C unit tests" should {
    "all pass at every stream configuration it is built for" in {
      val out = FirmwareBuild.make(this, Seq("test"))
      val (passed, failed) =
        Summary.findAllMatchIn(out).toVector.lastOption.map(m => m.group(1).toInt -> m.group(2).toInt)
          .getOrElse(fail(s"no summary line in make's output:\n${out.takeRight(2000)}"))
      failed shouldBe 0
      passed should be > 250
      info(s"$passed passed, $failed failed")
    }
  }

  /** The last `N passed, N failed` line of a make target's output, which must count no failure and some passes. */
  private def passes(out: String, atLeast: Int): Unit = {
    val (passed, failed) =
      Summary.findAllMatchIn(out).toVector.lastOption.map(m => m.group(1).toInt -> m.group(2).toInt)
        .getOrElse(fail(s"no summary line in make's output:\n${out.takeRight(2000)}"))
    failed shouldBe 0
    passed should be >= atLeast
    info(s"$passed passed, $failed failed")
  }

  private def missingForSdk(): Option[String] =
    FirmwareBuild.missingForHost().orElse {
      if (!FirmwareBuild.available("socat", "-V")) Some("socat is not installed (.ci/setup.d/socat.sh)")
      else if (!FirmwareBuild.available("python3", "-c", "import venv, ensurepip"))
        Some("python3 with venv is not installed (.ci/setup.d/python.sh)")
      else None
    }

  "The robot's body (docs/protocol.md 6.8, 6.9)" should {
    "answer the official DynamixelSDK on the emulated bus the posix robot and the qemu board read (make test-sdk)" in {
      passes(FirmwareBuild.make(this, Seq("test-sdk"), missing = () => missingForSdk()), 20)
    }
    "bridge requests in order over real UDP on the posix robot, and refuse them plain or with the gate closed " +
      "(make test-bridge)" in {
        passes(FirmwareBuild.make(this, Seq("test-bridge")), 6)
      }
    "read every servo and the camera over the qemu board's USART1 (make test-qemu-bus)" in {
      passes(FirmwareBuild.make(this, Seq("test-qemu-bus"), missing = () => FirmwareBuild.missingForArm()), 3)
    }
  }
}
