package style

import java.nio.charset.StandardCharsets.UTF_8
import java.nio.file.{Files, Path, Paths}

import scala.jdk.CollectionConverters._
import scala.util.Using

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** The main code keeps the 120 columns of .scalafmt.conf. The formatter (checked by .ci/run) keeps line breaks as
  * written and cannot split a long string or condition, so the width is checked here, in characters, not bytes.
  */
class SourceWidthSpec extends AnyWordSpec with Matchers {

  private val MaxColumns = 120

  /** Every Scala file under a `src/main` of the checkout (forked tests run in the checkout, the root module's folder).
    */
  private def mainSources(root: Path): Vector[Path] =
    Using.resource(Files.walk(root)) { paths =>
      paths.iterator.asScala
        .filter(p => p.toString.endsWith(".scala") && p.toString.contains("/src/main/"))
        .filterNot(p => p.toString.contains("/target/") || p.toString.contains("/.git/"))
        .toVector
    }

  "The main sources" should {
    "keep within 120 columns" in {
      val root = Paths.get("").toAbsolutePath
      val sources = mainSources(root)
      sources.size should be > 100
      val long = for {
        file <- sources
        (line, number) <- Files.readAllLines(file, UTF_8).asScala.zipWithIndex
        if line.length > MaxColumns
      } yield s"${root.relativize(file)}:${number + 1} (${line.length} columns)"
      long shouldBe empty
    }
  }
}
