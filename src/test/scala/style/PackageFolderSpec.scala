package style

import java.nio.charset.StandardCharsets.UTF_8
import java.nio.file.{Files, Path, Paths}

import scala.jdk.CollectionConverters._
import scala.util.Using

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** A class's package says where it lives: each package is declared under one module folder only (main and test
  * together), and each file sits in the folder its package names, so a reader finds a class from its import.
  */
class PackageFolderSpec extends AnyWordSpec with Matchers {

  private val Package = """^package\s+([\w.]+)\s*$""".r

  /** Every Scala file of the checkout's modules (forked tests run in the checkout, the root module's folder). */
  private def sources(root: Path): Vector[Path] =
    Using.resource(Files.walk(root)) { paths =>
      paths.iterator.asScala
        .filter(p => p.toString.endsWith(".scala") && p.toString.contains("/src/"))
        .filterNot(p => Seq("/target/", "/.git/", "/project/", "/examples/").exists(p.toString.contains))
        .toVector
    }

  /** The module folder of a source (the path before its `src/`) and its declared package. */
  private def located(root: Path, file: Path): Option[(String, String, String)] = {
    val relative = root.relativize(file).toString
    val module = relative.substring(0, relative.indexOf("src/"))
    Files.readAllLines(file, UTF_8).asScala.collectFirst { case Package(name) => (module, name, relative) }
  }

  "The Scala sources" should {
    val root = Paths.get("").toAbsolutePath
    val found = sources(root).flatMap(located(root, _))

    "declare each package under one module folder" in {
      found.size should be > 100
      val split = found.groupBy(_._2).collect {
        case (pkg, files) if files.map(_._1).distinct.size > 1 => s"$pkg in ${files.map(_._1).distinct.sorted}"
      }
      split shouldBe empty
    }

    "sit in the folder their package names" in {
      val misplaced = found.collect {
        case (_, pkg, path) if !path.contains(s"/scala/${pkg.replace('.', '/')}/") => s"$path declares $pkg"
      }
      misplaced shouldBe empty
    }
  }
}
