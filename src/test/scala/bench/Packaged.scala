package bench

import java.net.{DatagramSocket, InetAddress, ServerSocket}
import java.nio.file.{Files, Path, Paths}

import scala.jdk.OptionConverters._

/** What the benchmarks that run the installed package share: where the staged package is, free loopback ports, and a
  * process's CPU time.
  */
object Packaged {

  /** The package as `launcher/stage` leaves it (the `bench` alias stages it first). */
  val stage: Path = Paths.get("apps", "launcher", "target", "universal", "stage").toAbsolutePath

  /** One of the package's start scripts, e.g. `naogateway` or `robotctl`. */
  def bin(script: String): Path = stage.resolve("bin").resolve(script)

  /** Whether the package is staged. */
  def isStaged: Boolean = Files.isExecutable(bin("naogateway"))

  /** A TCP port on loopback that was free a moment ago. */
  def freeTcpPort(): Int = {
    val s = new ServerSocket(0, 1, InetAddress.getLoopbackAddress);
    try s.getLocalPort
    finally s.close()
  }

  /** A UDP port on loopback that was free a moment ago. */
  def freeUdpPort(): Int = {
    val s = new DatagramSocket(0, InetAddress.getLoopbackAddress);
    try s.getLocalPort
    finally s.close()
  }

  /** A process's CPU time (user + system) so far, in nanoseconds, as the operating system reports it. */
  def cpuNanos(pid: Long): Option[Long] =
    ProcessHandle.of(pid).toScala.flatMap(_.info().totalCpuDuration().toScala).map(_.toNanos)
}
