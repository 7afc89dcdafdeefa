package apps

import java.nio.charset.StandardCharsets
import java.nio.file.{Files, Path, Paths}

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

class WritingAppsDocSpec extends AnyWordSpec with Matchers {
  private def find(relative: String): Path =
    Seq(Paths.get("..", relative), Paths.get(relative)).find(Files.exists(_)).getOrElse(fail(s"$relative not found"))

  "docs/writing-apps.md" should {
    "show the first app exactly as it is compiled, in under 30 lines of code" in {
      val doc = new String(Files.readAllBytes(find("docs/writing-apps.md")), StandardCharsets.UTF_8)
      val source = new String(Files.readAllBytes(find("apps/src/main/scala/apps/examples/HelloRobot.scala")),
        StandardCharsets.UTF_8)
      doc should include(source)
      source.linesIterator.count(l =>
        l.trim.nonEmpty && !l.trim.startsWith("import") && !l.trim.startsWith("/**")) should be < 30
    }
  }
}
