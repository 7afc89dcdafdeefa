package naogateway.testkit

import java.nio.file.{Files, Path}

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

class TempFilesSpec extends AnyWordSpec with Matchers {

  /** A tree below `root`: a file, a nested directory with a file, an empty directory. */
  private def fill(root: Path): Unit = {
    Files.write(root.resolve("a.txt"), Array[Byte](1, 2))
    Files.write(Files.createDirectories(root.resolve("sub/deeper")).resolve("b.bin"), Array[Byte](3))
    Files.createDirectory(root.resolve("empty"))
    ()
  }

  "A temporary directory" should {
    "be there with its prefix during the body, and gone with everything in it afterwards" in {
      var seen: Option[Path] = None
      val result = TempFiles.withTempDir("tempfiles-spec") { dir =>
        seen = Some(dir)
        Files.isDirectory(dir) shouldBe true
        dir.getFileName.toString should startWith("tempfiles-spec")
        fill(dir)
        42
      }
      result shouldBe 42
      Files.exists(seen.get) shouldBe false
    }

    "be gone when the body throws, and the body's exception be the one thrown" in {
      var seen: Option[Path] = None
      val thrown = the[IllegalStateException] thrownBy TempFiles.withTempDir("tempfiles-spec") { dir =>
        seen = Some(dir)
        fill(dir)
        throw new IllegalStateException("the body failed")
      }
      thrown.getMessage shouldBe "the body failed"
      Files.exists(seen.get) shouldBe false
    }

    "delete a symbolic link in it, never what the link points to" in {
      TempFiles.withTempDir("tempfiles-spec-outside") { outside =>
        val kept = Files.write(outside.resolve("kept.txt"), Array[Byte](7))
        TempFiles.withTempDir("tempfiles-spec") { dir =>
          Files.createSymbolicLink(dir.resolve("to-dir"), outside)
          Files.createSymbolicLink(dir.resolve("to-file"), kept)
          Files.createSymbolicLink(dir.resolve("dangling"), outside.resolve("no-such-file"))
        }
        Files.readAllBytes(kept).toVector shouldBe Vector[Byte](7)
      }
    }
  }

  "A temporary file" should {
    "be gone after the body, also when the body made it a directory" in {
      var seen = Vector.empty[Path]
      TempFiles.withTempFile("tempfiles-spec", ".log") { file =>
        seen :+= file
        Files.isRegularFile(file) shouldBe true
        file.getFileName.toString should endWith(".log")
      }
      TempFiles.withTempFile("tempfiles-spec", ".dir") { file =>
        seen :+= file
        Files.delete(file)
        Files.createDirectory(file)
        fill(file)
      }
      seen.filter(Files.exists(_)) shouldBe empty
    }
  }

  "Deleting recursively" should {
    "take a missing path, and a file the body already deleted, as done" in {
      TempFiles.withTempDir("tempfiles-spec") { dir =>
        Files.delete(dir)
        TempFiles.deleteRecursively(dir.resolve("never-made"))
      }
    }
  }
}
