package naogateway.testkit

import java.io.IOException
import java.nio.file.{FileVisitResult, Files, LinkOption, NoSuchFileException, Path, SimpleFileVisitor}
import java.nio.file.attribute.BasicFileAttributes

/** Temporary directories and files for specs that are gone when the spec is done, whatever its outcome: left behind,
  * every test run would add more of them to the system's temporary directory.
  */
object TempFiles {

  /** Runs `body` with a fresh temporary directory whose name begins with `prefix`, then deletes the directory and all
    * it holds, whether `body` returned or threw.
    */
  def withTempDir[A](prefix: String)(body: Path => A): A = {
    val dir = Files.createTempDirectory(prefix)
    cleaningUp(dir)(body(dir))
  }

  /** Runs `body` with a fresh temporary file named `prefix`...`suffix`, then deletes it (and, should `body` have made a
    * directory of it, all that holds), whether `body` returned or threw.
    */
  def withTempFile[A](prefix: String, suffix: String)(body: Path => A): A = {
    val file = Files.createTempFile(prefix, suffix)
    cleaningUp(file)(body(file))
  }

  /** Evaluates `body`, then deletes `path` recursively. A failure to delete is the spec's failure when `body`
    * succeeded, and is attached to `body`'s own failure (suppressed) when it did not, so it never hides the cause.
    */
  def cleaningUp[A](path: Path)(body: => A): A = {
    val result =
      try body
      catch {
        case t: Throwable =>
          try deleteRecursively(path)
          catch { case e: IOException => t.addSuppressed(e) }
          throw t
      }
    deleteRecursively(path)
    result
  }

  /** Deletes `root` and, if it is a directory, everything under it, deepest first. Symbolic links are deleted, never
    * followed, so nothing outside `root` is touched; a file that is already gone is no error, nor is a missing `root`.
    */
  def deleteRecursively(root: Path): Unit =
    if (Files.exists(root, LinkOption.NOFOLLOW_LINKS)) {
      Files.walkFileTree(
        root,
        new SimpleFileVisitor[Path] {
          override def visitFile(file: Path, attrs: BasicFileAttributes): FileVisitResult = {
            Files.deleteIfExists(file)
            FileVisitResult.CONTINUE
          }

          override def visitFileFailed(file: Path, e: IOException): FileVisitResult = e match {
            case _: NoSuchFileException => FileVisitResult.CONTINUE
            case _                      => throw e
          }

          override def postVisitDirectory(dir: Path, e: IOException): FileVisitResult = {
            if (e != null && !e.isInstanceOf[NoSuchFileException]) throw e
            Files.deleteIfExists(dir)
            FileVisitResult.CONTINUE
          }
        }
      )
      ()
    }
}
