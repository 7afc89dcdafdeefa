package firmware

import java.io.File
import java.nio.charset.StandardCharsets
import java.nio.file.Files
import java.util.concurrent.TimeUnit

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.util.Try

import org.scalatest.Assertions

/** Builds the C firmware (firmware/Makefile) for a spec. A spec calls `make(...)`, which runs make in firmware/ and
  * cancels the spec with the reason when a tool is missing (make, a C compiler, nanopb, the ARM toolchain, QEMU:
  * install them with `bash firmware/setup.sh`), and fails it when the build itself fails.
  */
object FirmwareBuild {

  /** The checkout's firmware/ folder. */
  lazy val dir: File =
    Iterator.iterate(new File(".").getAbsoluteFile)(_.getParentFile).takeWhile(_ != null)
      .map(new File(_, "firmware")).find(d => new File(d, "Makefile").isFile)
      .getOrElse(throw new IllegalStateException("cannot find firmware/Makefile from " + new File(".").getAbsolutePath))

  /** Whether `command` runs (exit status 0) within 30 s. */
  def available(command: String*): Boolean =
    Try {
      val p = new ProcessBuilder(command.asJava).redirectErrorStream(true).redirectOutput(
        ProcessBuilder.Redirect.DISCARD).start()
      p.waitFor(30, TimeUnit.SECONDS) && p.exitValue() == 0
    }.getOrElse(false)

  /** What is missing for the host build, if anything. */
  def missingForHost(): Option[String] =
    if (!available("make", "--version")) Some("make is not installed")
    else if (!available("cc", "--version")) Some("no C compiler (cc) is installed")
    else if (!available("sh", "-c", "command -v nanopb_generator.py"))
      Some("nanopb's generator is not installed (bash firmware/setup.sh)")
    else if (!new File(dir, "build/third_party/nanopb/pb_decode.c").isFile)
      Some("nanopb's C runtime is not unpacked in firmware/build/third_party (bash firmware/setup.sh)")
    else None

  /** What is missing for the ARM and QEMU builds, if anything (the host build's needs included). */
  def missingForArm(): Option[String] =
    missingForHost().orElse {
      if (!available("arm-none-eabi-gcc", "--version"))
        Some("arm-none-eabi-gcc is not installed (bash firmware/setup.sh)")
      else if (!available("qemu-system-arm", "--version"))
        Some("qemu-system-arm is not installed (bash firmware/setup.sh)")
      else None
    }

  /** Runs `make -C firmware targets` (with `variables` as NAME=value) once per distinct argument list in this JVM;
    * cancels through `a` when `missing` names a missing tool, fails through `a` when make fails. Returns make's output.
    */
  def make(a: Assertions, targets: Seq[String], variables: Map[String, String] = Map.empty,
      missing: () => Option[String] = () => missingForHost(), within: FiniteDuration = 5.minutes): String = {
    missing().foreach(why => a.cancel(s"firmware not built: $why"))
    val args = targets ++ variables.toSeq.sorted.map { case (k, v) => s"$k=$v" }
    val result = synchronized(built.getOrElseUpdate(args, run(args, within)))
    result match {
      case Right(out) => out
      case Left(out)  => a.fail(s"make ${args.mkString(" ")} failed:\n${out.takeRight(4000)}")
    }
  }

  private val built = scala.collection.mutable.Map.empty[Seq[String], Either[String, String]]

  private def run(args: Seq[String], within: FiniteDuration): Either[String, String] = {
    val log = Files.createTempFile("firmware-make", ".log").toFile
    try {
      val p = new ProcessBuilder((Seq("make", "-C", dir.getPath, "-j2") ++ args).asJava)
        .redirectErrorStream(true).redirectOutput(log).start()
      val finished = p.waitFor(within.toSeconds, TimeUnit.SECONDS)
      if (!finished) p.destroyForcibly()
      val out = new String(Files.readAllBytes(log.toPath), StandardCharsets.UTF_8)
      if (finished && p.exitValue() == 0) Right(out)
      else Left(if (finished) out else s"$out\n(make did not end within $within)")
    } finally log.delete()
  }
}
