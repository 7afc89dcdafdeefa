package bench

import java.io.File
import java.nio.charset.StandardCharsets
import java.nio.file.Files

import scala.collection.immutable.ListMap
import scala.util.Try

import org.scalatest.Assertions
import org.scalatest.exceptions.{TestCanceledException, TestFailedException}

import firmware.FirmwareBuild

/** The robot-side C library's footprint, measured as the thesis measured its firmware (§7): `make -C firmware
  * footprint` builds the CM-530 images and runs the measurement program in qemu (port/qemu/measure.c, footprint.py).
  *
  *   - `firmware_library_flash_bytes_w1` / `_w4`, `firmware_library_static_ram_bytes_w1` / `_w4`: the library (library,
  *     GS1500M driver, nanopb, descriptors, libc, board port) measured with a stub program that keeps every public
  *     `fr.h` function, stream window 1 (stop-and-wait) and 4 (selective repeat);
  *   - `firmware_example_flash_bytes_w1` / `_w4`, `firmware_example_static_ram_bytes_w1` / `_w4`: the test robot's
  *     image, apart; static RAM is `.data` + `.bss` + `.noinit` + the stack guard, the stack apart;
  *   - `firmware_stack_<entry>_bytes`: the deepest stack of each entry point, by painting it (W = 1);
  *   - `firmware_<entry>_instructions`: instructions of each entry point under `-icount` (deterministic): a keep-alive
  *     (encode, frame; then signed), the framing alone, a request (parse, decode, dispatch, answer), an idle poll.
  *
  * Goals (docs/firmware.md): flash ≤ 20 KB, static RAM ≤ 6 KB (W = 1) / ≤ 14 KB (W = 4), stack ≤ 1 KB, keep-alive ≤
  * 8,000 instructions / ≤ 20,000 signed. Without the ARM toolchain or qemu it is skipped with the reason, and gives no
  * figures.
  */
object FirmwareBench extends Benchmark {
  val name = "firmware"

  def run(): ListMap[String, Double] = {
    val asserting = new Assertions {}
    Try(FirmwareBuild.make(asserting, Seq("footprint"), missing = () => FirmwareBuild.missingForArm())).fold(
      {
        case c: TestCanceledException =>
          println(s"firmware: skipped, ${c.getMessage}")
          ListMap.empty
        case f: TestFailedException => throw new IllegalStateException(f.getMessage)
        case e                      => throw e
      },
      _ => figures(new File(FirmwareBuild.dir, "build/footprint.json"))
    )
  }

  private val Figure = """"(firmware_[a-z_0-9]+)":\s*(\d+)""".r

  /** The flat `figures` of footprint.json (footprint.py writes each `firmware_` key once, in this order). */
  def figures(file: File): ListMap[String, Double] = {
    val json = new String(Files.readAllBytes(file.toPath), StandardCharsets.UTF_8)
    val found = ListMap.from(Figure.findAllMatchIn(json).map(m => m.group(1) -> m.group(2).toDouble))
    require(found.contains("firmware_keepalive_instructions"), s"no figures in $file")
    found
  }
}
