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

  /** The JVM options `bin/naogateway` gives the gateway (build.sbt: the JIT's, and the performance counters' sampling),
    * for a figure of the gateway taken in a JVM of the bench's own; [[checkJvmOptions]] holds them to the staged
    * script.
    */
  val jvmOptions: Seq[String] = Seq("-XX:TieredStopAtLevel=1", "-XX:CompileThresholdScaling=0.1",
    "-XX:C1MaxInlineSize=70", "-XX:PerfDataSamplingInterval=1000")

  /** Fails when the staged `bin/naogateway` no longer gives its JVM every one of [[jvmOptions]]. */
  def checkJvmOptions(): Unit = if (isStaged) {
    val script = new String(Files.readAllBytes(bin("naogateway")), java.nio.charset.StandardCharsets.UTF_8)
    val missing = jvmOptions.filterNot(o => script.contains(s"addJava \"$o\""))
    require(missing.isEmpty, s"bin/naogateway no longer passes ${missing.mkString(" ")}: update bench.Packaged")
  }

  /** A TCP port on loopback that was free a moment ago. */
  /** Gives a demo process started with `env` ports of its own and its log at `log`, so a demo or test running beside
    * the bench is neither disturbed nor counted.
    */
  def ownPorts(env: java.util.Map[String, String], log: java.nio.file.Path): Unit = {
    env.put("ROBOTS_GATEWAY_PORT", freeTcpPort().toString)
    env.put("NAOGATEWAY_GAMECONTROLLER_PORT", freeUdpPort().toString)
    env.put("NAOGATEWAY_ZEROMQ_BIND", "tcp://127.0.0.1:*")
    env.put("NAOGATEWAY_ZEROMQ_PUBLISH", "tcp://127.0.0.1:*")
    env.put("NAOGATEWAY_LOG_FILE", log.toString)
    env.put("NAOGATEWAY_CONTROL", s"127.0.0.1:${freeTcpPort()}")
    env.put("NAOGATEWAY_DATAGRAM_DOOR_PORT", freeUdpPort().toString)
    env.put("NAOGATEWAY_WEB_PORT", "0")
    ()
  }

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
