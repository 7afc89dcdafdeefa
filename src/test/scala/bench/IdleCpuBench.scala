package bench

import java.lang.management.ManagementFactory
import java.net.{InetAddress, InetSocketAddress, StandardProtocolFamily}
import java.nio.ByteBuffer
import java.nio.channels.{AsynchronousCloseException, DatagramChannel}
import java.nio.charset.StandardCharsets
import java.nio.file.{Files, Path, Paths}
import java.util.concurrent.TimeUnit

import scala.collection.immutable.ListMap
import scala.concurrent.Await
import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.util.Try

import akka.actor.typed.ActorSystem
import akka.actor.typed.scaladsl.Behaviors
import com.typesafe.config.ConfigFactory

import naogateway.testkit.TestLoopback
import naogateway.sim.{Fleet, FleetSettings}

/** What doing nothing costs, in percent of one core of this machine:
  *
  *   - `demo_idle_cpu_pct`: the demo as a user starts it, the staged package's `bin/naogateway` (falling back to the
  *     launcher's `main` in a JVM forked with this classpath when no package is staged): gateway, middleware, three
  *     simulated robots with the faithful link, the ball follower in its own actor system, the simulated GameController
  *     and the status printer, output piped. Once the launcher's log shows the three robots online, [[DemoSettle]] lets
  *     the JIT calm down, then the process's CPU time (user + system, from the operating system) is taken over
  *     [[Window]]. The ball follower has walked robot 1 to the ball by then and stands at it, its camera resting
  *     between looks, so this is the demo's steady state rather than a process with nothing to do. The log is read for
  *     the ball follower too: a demo whose ball follower did not get its robot (a machine too loaded for its 10 s
  *     search) is a different, cheaper demo. The progress shows the window per thread group ([[ThreadCpu]]): CPU and
  *     wake-ups a second.
  *   - `demo_stop_ms`: from the bench's TERM to the demo's exit, the JVM's shutdown hooks doing what they do on Ctrl-C
  *     (both nodes leave the cluster, the actor systems stop). Goal 2000 (launcher.conf).
  *   - `sim_idle_cpu_pct_per_robot`: [[SimRobots]] simulated robots with the faithful link (the demo's mode) in an
  *     actor system of this JVM, sending their 5 Hz keep-alives to a sink (one thread reading and discarding), nothing
  *     else asked of them. The JVM's process CPU time over [[Window]] after [[SimSettle]], divided by the robots; the
  *     JVM's own share (GC, JIT, Akka's scheduler tick, the sink thread) is in it, so the figure errs high.
  */
object IdleCpuBench extends Benchmark {
  val name = "idle"
  override val quietSensitive = true

  private val Window = 30.seconds
  // The JIT compiler is still busy a minute after the start (about 5 % of a core at 80 s, under 2 % at 3 min).
  private val DemoSettle = 120.seconds
  private val SimSettle = 10.seconds
  private val SimRobots = 20
  private val OnlineTimeout = 120.seconds

  def run(): ListMap[String, Double] = {
    val (idle, stop) = demoIdle()
    ListMap("demo_idle_cpu_pct" -> idle, "demo_stop_ms" -> stop, "sim_idle_cpu_pct_per_robot" -> simIdlePerRobot())
  }

  private def progress(line: String): Unit = println(s"  idle: $line")

  /** The demo's idle CPU, and how long it took to exit once told to stop (NaN where it did not get that far). */
  private def demoIdle(): (Double, Double) = {
    val log = Paths.get("target", "bench", "demo-idle.log").toAbsolutePath
    Files.createDirectories(log.getParent)
    Files.deleteIfExists(log)
    // The package's launcher, as a user starts it (the bench alias stages the package first); without a staged
    // package, the launcher's main on this classpath with the launcher's own logging, not the tests' logback-test.xml.
    import Packaged.ownPorts
    val command =
      if (Packaged.isStaged) Seq(Packaged.bin("naogateway").toString)
      else {
        val javaBin = s"${System.getProperty("java.home")}/bin/java"
        val logging =
          Option(getClass.getClassLoader.getResource("logback.xml")).map(u => s"-Dlogback.configurationFile=$u")
        Seq(javaBin) ++ logging ++ Seq("-cp", System.getProperty("java.class.path"), "naogateway.launcher.Launcher")
      }
    progress(s"demo: ${command.head}")
    val builder = new ProcessBuilder(command.asJava)
      .redirectErrorStream(true)
      .redirectOutput(ProcessBuilder.Redirect.DISCARD)
    ownPorts(builder.environment(), log)
    val process = builder.start()
    var stopMs = Double.NaN
    val idle =
      try {
        val deadline = OnlineTimeout.fromNow
        def online: Int = onlineRobots(log)
        while (online < 3 && process.isAlive && deadline.hasTimeLeft()) Thread.sleep(500)
        if (online < 3) {
          progress(s"the demo showed $online of 3 robots online (see $log)")
          Double.NaN
        } else {
          progress(s"three robots online; settling ${DemoSettle.toSeconds} s, then measuring ${Window.toSeconds} s")
          Thread.sleep(DemoSettle.toMillis)
          if (!logHas(log, "Ball follower has robot"))
            progress(s"WARNING: the ball follower has no robot (see $log): this figure is not the demo's")
          def cpu(): Option[Long] = Packaged.cpuNanos(process.pid())
          val (c0, t0) = (cpu(), System.nanoTime())
          // The window itself, spent reading where the CPU goes and how often each thread group wakes.
          val threads = ThreadCpu.window(process.pid(), Window)
          val (c1, t1) = (cpu(), System.nanoTime())
          val pct = (for (a <- c0; b <- c1) yield (b - a) * 100.0 / (t1 - t0)).getOrElse(Double.NaN)
          progress(f"demo process: $pct%.1f %% of one core over ${(t1 - t0) / 1e9}%.0f s, per thread group:")
          ThreadCpu.lines(threads).foreach(l => progress(s"  $l"))
          // A TERM runs the JVM's shutdown hooks as Ctrl-C does: both nodes leave the cluster and stop (goal 2 s).
          val told = System.nanoTime()
          process.destroy()
          if (process.waitFor(20, TimeUnit.SECONDS)) {
            stopMs = (System.nanoTime() - told) / 1e6
            progress(f"the demo exited $stopMs%.0f ms after TERM")
          }
          pct
        }
      } finally {
        process.destroy()
        if (!process.waitFor(20, TimeUnit.SECONDS)) process.destroyForcibly()
      }
    (idle, stopMs)
  }

  private def logHas(log: Path, text: String): Boolean =
    Try(Files.readAllLines(log, StandardCharsets.UTF_8).asScala.exists(_.contains(text))).getOrElse(false)

  // "Robot [n] online at": the gateway's log line when a robot comes online.
  private def onlineRobots(log: Path): Int =
    Try(Files.readAllLines(log, StandardCharsets.UTF_8).asScala.collect {
      case l if l.contains("online at") => l.substring(l.indexOf("Robot [")).takeWhile(_ != ']')
    }.toSet.size).getOrElse(0)

  private def simIdlePerRobot(): Double = {
    val sink = DatagramChannel.open(StandardProtocolFamily.INET)
    sink.bind(new InetSocketAddress(InetAddress.getLoopbackAddress, 0))
    val reader = new Thread(
      () => {
        val buffer = ByteBuffer.allocate(2048)
        try while (true) { buffer.clear(); sink.receive(buffer) }
        catch { case _: AsynchronousCloseException => () }
      },
      "idle-bench-sink"
    )
    reader.setDaemon(true)
    reader.start()
    val config = ConfigFactory.parseString("akka.loglevel = WARNING").withFallback(ConfigFactory.load())
    val system = ActorSystem[Nothing](Behaviors.empty, "idle-bench-robots", config)
    try {
      val target = sink.getLocalAddress.asInstanceOf[InetSocketAddress]
      val fleet = Await.result(Fleet.start(system,
          FleetSettings(target, (1 to SimRobots).toVector, firstAddress = TestLoopback.block(SimRobots))), 60.seconds)
      progress(
        s"${fleet.robots.size} simulated robots up; settling ${SimSettle.toSeconds} s, then measuring ${Window.toSeconds} s")
      Thread.sleep(SimSettle.toMillis)
      val os = ManagementFactory.getOperatingSystemMXBean.asInstanceOf[com.sun.management.OperatingSystemMXBean]
      val (c0, t0) = (os.getProcessCpuTime, System.nanoTime())
      Thread.sleep(Window.toMillis)
      val (c1, t1) = (os.getProcessCpuTime, System.nanoTime())
      val pct = (c1 - c0) * 100.0 / (t1 - t0)
      progress(f"$SimRobots robots: the whole JVM $pct%.2f %% of one core, ${pct / SimRobots}%.3f %% per robot")
      Await.result(fleet.stop(), 30.seconds)
      pct / SimRobots
    } finally {
      system.terminate()
      Await.ready(system.whenTerminated, 30.seconds)
      sink.close()
    }
  }
}
