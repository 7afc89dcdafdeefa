package apps.zeromq

import java.io.File
import java.nio.charset.StandardCharsets
import java.nio.file.Files
import java.util.concurrent.TimeUnit

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.util.{Try, Using}

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.testkit.TempFiles.{withTempDir, withTempFile}

/** The Python client as a package: pip installs it from the repository, and the Python tests' environment says why it
  * cannot be made.
  */
class PythonPackageSpec extends AnyWordSpec with Matchers {

  private def python3Present: Boolean =
    Try(new ProcessBuilder("python3", "--version").start().waitFor() == 0).getOrElse(false)

  /** Runs `command` in `dir` with `env`; its exit code and output. */
  private def run(command: Seq[String], dir: File, env: Map[String, String], within: FiniteDuration): (Int, String) =
    withTempFile("python-package", ".log") { log =>
      val builder =
        new ProcessBuilder(command.asJava).directory(dir).redirectErrorStream(true).redirectOutput(log.toFile)
      env.foreach { case (k, v) => builder.environment().put(k, v) }
      val process = builder.start()
      if (!process.waitFor(within.toSeconds, TimeUnit.SECONDS)) {
        process.destroyForcibly(); fail(s"${command.mkString(" ")} took over $within")
      }
      process.exitValue() -> new String(Files.readAllBytes(log), StandardCharsets.UTF_8)
    }

  "The Python tests' environment" should {
    "give the reason, for the tests to cancel with, when pip cannot reach a package registry" in {
      assume(python3Present, "python3 is not available")
      val venv = new File(PythonEnv.root, "apps/target/python-venv-offline")
      // No network, as pip sees it: an index nobody answers on, no retries, no cache, no user config.
      val offline = Map("PIP_INDEX_URL" -> "http://127.0.0.1:9/simple/", "PIP_RETRIES" -> "0", "PIP_TIMEOUT" -> "1",
        "PIP_NO_CACHE_DIR" -> "1", "PIP_CONFIG_FILE" -> "/dev/null")
      val result = PythonEnv.environment(venv, env = offline)
      result match {
        case Left(why) if why.startsWith("python3 -m venv failed") => cancel(why)
        case Left(why) =>
          why should startWith(
            "pip could not install apps/python/requirements.txt (no network or no package registry?)")
          venv.exists() shouldBe false // nothing half-made is left to be reused
        case Right(_) => fail("pip installed the requirements from an index that does not exist")
      }
    }
  }

  "The Python client" should {
    "install with pip from the repository, carrying its .proto files, and generate its classes from them" in {
      val python = PythonEnv.python()
      withTempDir("naogateway-client-install") { work =>
        val site = work.resolve("site")
        val (code, out) = run(
          Seq(
            python.getPath,
            "-m",
            "pip",
            "install",
            "--disable-pip-version-check",
            "-q",
            "--no-deps",
            "--no-build-isolation",
            "--target",
            site.toString,
            new File(PythonEnv.root, "apps/python").getPath
          ),
          PythonEnv.root,
          Map.empty,
          3.minutes
        )
        withClue(out) { code shouldBe 0 }
        val protos = site.resolve("naogateway_client/proto/naogateway/proto")
        Files.isRegularFile(protos.resolve("rpc.proto")) shouldBe true
        Files.isSymbolicLink(site.resolve("naogateway_client/proto")) shouldBe false
        // Imported from the installed copy, away from the checkout.
        val check = "import naogateway_client, naogateway_recording; naogateway_client.load_protos(); " +
          "print(naogateway_client.__file__); print(naogateway_client.rpc_pb2.DESCRIPTOR.package)"
        val (importCode, printed) = run(
          Seq(python.getPath, "-c", check),
          work.toFile,
          Map("PYTHONPATH" -> site.toString, "NAOGATEWAY_PY_GEN" -> work.resolve("gen").toString,
            "PYTHONDONTWRITEBYTECODE" -> "1"),
          2.minutes
        )
        withClue(printed) {
          importCode shouldBe 0
          val lines = printed.linesIterator.toVector
          lines.head should startWith(site.toString)
          lines should contain("naogateway.proto")
        }
        // Without a folder named for them the classes go to a temporary one, gone when the program ends.
        val tmp = Files.createDirectories(work.resolve("tmp"))
        val (tmpCode, tmpPrinted) = run(
          Seq(python.getPath, "-c", "import naogateway_client as c; c.load_protos(); print(c.rpc_pb2.__file__)"),
          work.toFile,
          Map("PYTHONPATH" -> site.toString, "TMPDIR" -> tmp.toString, "NAOGATEWAY_PY_GEN" -> "",
            "PYTHONDONTWRITEBYTECODE" -> "1"),
          2.minutes
        )
        withClue(tmpPrinted) {
          tmpCode shouldBe 0
          tmpPrinted.linesIterator.toVector.last should startWith(tmp.toString) // generated there, while it ran
          Using.resource(Files.list(tmp))(_.iterator.asScala.toVector) shouldBe empty
        }
      }
    }
  }
}
