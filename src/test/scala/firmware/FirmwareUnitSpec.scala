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
}
