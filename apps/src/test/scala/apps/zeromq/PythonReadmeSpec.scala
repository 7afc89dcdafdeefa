package apps.zeromq

import java.io.File
import java.nio.charset.StandardCharsets
import java.nio.file.Files

import scala.concurrent.duration._
import scala.util.Try

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** The Python client's README is its reference: every public method and function of `naogateway_client`, with its
  * arguments and its result, is a row of the README's tables, and every row is one of them. The module is read by
  * Python's own parser (`ast`, src/test/resources/python/public_api.py), so only `python3` is needed, not the venv.
  */
class PythonReadmeSpec extends AnyWordSpec with Matchers {

  private val root = PythonEnv.root
  private val readme = new File(root, "apps/python/README.md")
  private val module = new File(root, "apps/python/naogateway_client/__init__.py")

  /** The README's rows: "`call`" and "`returns`" of every table whose first column is `call`. */
  private def readmeRows: Set[String] = {
    val text = new String(Files.readAllBytes(readme.toPath), StandardCharsets.UTF_8)
    val Row = """\| `([^`]+)` \| `([^`]+)` \|.*""".r
    text.linesIterator.collect { case Row(call, returns) => s"$call\t$returns" }.toSet
  }

  private def moduleRows: Set[String] = {
    val python = Try(new ProcessBuilder("python3", "--version").start().waitFor()).toOption.contains(0)
    if (!python) cancel("python3 is not installed: the README cannot be checked against the module")
    val script = new File(getClass.getResource("/python/public_api.py").toURI)
    val log = Files.createTempFile("public-api", ".log").toFile
    try {
      val (code, output) = PythonEnv.run(Seq("python3", script.getPath, module.getPath), 60.seconds, log)
      withClue(output)(code shouldBe 0)
      output.linesIterator.filter(_.nonEmpty).toSet
    } finally { log.delete(); () }
  }

  "The Python client's README" should {
    "list every public method and function of naogateway_client with its arguments and result, and nothing else" in {
      val inModule = moduleRows
      val inReadme = readmeRows
      withClue("in the module, missing from the README: ")(inModule -- inReadme shouldBe empty)
      withClue("in the README, not in the module: ")(inReadme -- inModule shouldBe empty)
      // The calls a newcomer needs first are there (a table of nothing would pass the two lines above).
      inReadme should contain allOf ("status(robot_id)\tStatus", "acquire(robot_id, *groups)\tbool",
        "head(robot_id, pan, tilt)\tbool", "release(robot_id, *groups)\tbool")
    }
  }
}
