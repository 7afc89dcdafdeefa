package bench

import java.io.File
import java.lang.management.ManagementFactory
import java.nio.file.Files

import scala.collection.immutable.ListMap
import scala.concurrent.Await
import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.util.Try

import akka.actor.typed.ActorSystem
import akka.actor.typed.scaladsl.Behaviors
import com.typesafe.config.ConfigFactory

import apps.web.{Browser, WebDemo, WebSettings}
import apps.zeromq.PythonEnv
import naogateway.access.GatewayAccess
import naogateway.api.{GameStateUpdated, GatewayEvent}

/** What the web view costs (docs/web.md, "What it costs"): the demo of [[WebDemo]] (three simulated robots with the
  * faithful link, the simulated GameController, gateway and middleware) in one JVM with Akka's pools sized as the
  * package sizes them (launcher.conf), first without the web view's clients, then with the page open in headless
  * Chromium and a Foxglove-protocol viewer subscribed to every channel (src/test/python/bench/foxglove_reader.py, a
  * process of its own); the progress shows each window per thread group ([[ThreadCpu]]):
  *
  *   - `web_idle_cpu_pct_without` / `web_idle_cpu_pct`: this JVM's CPU time (user + system) over [[Window]], in percent
  *     of one core, without and with the clients (Chromium's and the viewer's own CPU is not counted: it is the
  *     viewer's machine's; the viewer's is printed beside it);
  *   - `web_heap_growth_mb`: heap in use after a full collection, at the end of the window with clients against before
  *     they connected;
  *   - `web_change_latency_ms_p50` / `_max`: from the gateway publishing a new game state (a subscriber's clock) to the
  *     page showing it (the page's clock, the same machine's).
  */
object WebBench extends Benchmark {
  val name = "web"
  override val quietSensitive = true

  // The JVM options the package gives the gateway (C1 only, and sooner), so the figure is the installed base station's.
  override def jvmOptions: Seq[String] = Packaged.jvmOptions

  private val Window = 30.seconds
  private val Settle = 20.seconds
  // The page and the feed make new code hot (JSON, WebSocket frames, the feed's encoding): 20 s after they connect the
  // JIT still took half of the window's CPU (7 of 13.9 % at load 8), which a base station running for hours never pays.
  private val ClientSettle = 60.seconds

  private def progress(line: String): Unit = println(s"  web: $line")

  private def cpuNanos(): Long =
    ManagementFactory.getOperatingSystemMXBean.asInstanceOf[com.sun.management.OperatingSystemMXBean].getProcessCpuTime

  private def heapAfterGc(): Long = {
    (1 to 3).foreach { _ => System.gc(); Thread.sleep(200) }
    val heap = ManagementFactory.getMemoryMXBean.getHeapMemoryUsage
    heap.getUsed
  }

  private def cpuPercent(window: FiniteDuration): Double = {
    val start = cpuNanos()
    val wall = System.nanoTime()
    // The window itself, spent reading where this JVM's CPU goes and how often each thread group wakes.
    val threads = ThreadCpu.window(ProcessHandle.current().pid(), window)
    val pct = 100.0 * (cpuNanos() - start) / (System.nanoTime() - wall)
    ThreadCpu.lines(threads).foreach(l => progress(s"  $l"))
    pct
  }

  def run(): ListMap[String, Double] = {
    Packaged.checkJvmOptions()
    // Akka's pools as the package sizes them and its scheduler's tick (launcher.conf), so the figure is the installed
    // base station's.
    val launcher = naogateway.launcher.Launcher.defaults
    val pools = launcher.withOnlyPath("akka.actor.default-dispatcher")
      .withFallback(launcher.withOnlyPath("akka.actor.internal-dispatcher"))
      .withFallback(launcher.withOnlyPath("akka.scheduler.tick-duration")).resolve()
    val config =
      ConfigFactory.parseString("apps.web { push-interval = 250ms, sample-interval = 1s }").withFallback(pools)
        .withFallback(WebDemo.config)
    val system = ActorSystem[Nothing](Behaviors.empty, "web-bench", config)
    try {
      val demo = new WebDemo(system, WebSettings(system))
      progress(s"demo up, web view at ${demo.page()}; settling ${Settle.toSeconds} s")
      Thread.sleep(Settle.toMillis)
      val without = cpuPercent(Window)
      progress(
        f"without clients: $without%.1f %% of a core (load average ${ManagementFactory.getOperatingSystemMXBean.getSystemLoadAverage}%.2f)")
      val heapBefore = heapAfterGc()

      // The gateway's own moment of each new game state.
      @volatile var published = Vector.empty[(String, Long)]
      val events = system.systemActorOf(
        Behaviors.receiveMessage[GatewayEvent] {
          case GameStateUpdated(d) =>
            val state = apps.StatusView.stateName(d.gameState)
            if (published.lastOption.forall(_._1 != state)) published :+= state -> System.currentTimeMillis()
            Behaviors.same
          case _ => Behaviors.same
        },
        "web-bench-events"
      )
      demo.gateway ! GatewayAccess.Subscribe(events)

      // A Foxglove viewer that subscribes to every channel it is advertised, in a process of its own as a real one is:
      // its own reading of the messages is the viewer's machine's work, not the gateway's.
      val viewerLog = new File(PythonEnv.root, "target/bench/foxglove-reader.log")
      viewerLog.getParentFile.mkdirs()
      val viewer = PythonEnv.environment().map { python =>
        new ProcessBuilder(
          python.getPath,
          "-u",
          new File(PythonEnv.root, "src/test/python/bench/foxglove_reader.py")
            .getPath,
          s"ws://127.0.0.1:${demo.address.getPort}/foxglove",
          (ClientSettle + Window + 30.seconds).toSeconds
            .toString
        ).redirectErrorStream(true).redirectOutput(viewerLog).start()
      }
      // "count N": the viewer's messages so far, printed once a second.
      def viewerCount(): Long =
        Try(Files.readAllLines(viewerLog.toPath).asScala.reverseIterator.collectFirst {
          case l if l.startsWith("count ") => l.split(' ')(1).toLong
        }.getOrElse(0L)).getOrElse(0L)
      def viewerCpu(): Option[Long] = viewer.toOption.flatMap(p => Packaged.cpuNanos(p.pid()))

      val withClients = (Browser.missing.map(r => s"no browser ($r)") ++ viewer.left.toOption.map(r =>
        s"no Foxglove viewer ($r)")).headOption match {
        case Some(reason) =>
          progress(s"$reason: the page's and the feed's figures are left out")
          ListMap("web_idle_cpu_pct_without" -> without)
        case None =>
          Browser.withChromium() { driver =>
            driver.get(demo.page())
            Thread.sleep(ClientSettle.toMillis)
            val (messages0, viewer0, wall0) = (viewerCount(), viewerCpu(), System.nanoTime())
            val cpu = cpuPercent(Window)
            val (messages1, viewer1, wall1) = (viewerCount(), viewerCpu(), System.nanoTime())
            val viewerPct =
              (for (a <- viewer0; b <- viewer1) yield (b - a) * 100.0 / (wall1 - wall0)).getOrElse(Double.NaN)
            val heapAfter = heapAfterGc()
            progress(
              f"with the page and a Foxglove viewer: $cpu%.1f %% of a core (load average ${ManagementFactory.getOperatingSystemMXBean.getSystemLoadAverage}%.2f), heap ${(heapAfter - heapBefore) / 1e6}%+.1f MB, " +
                f"${messages1 - messages0} Foxglove messages in the window (the viewer's own process: $viewerPct%.1f %% of a core, not counted)")
            val changes = driver.executeScript("return window.naogateway.changes").asInstanceOf[java.util.List[
              java.util.Map[String, AnyRef]]]
              .asScala.toVector.map(m => m.get("state").toString -> m.get("at").asInstanceOf[Number].longValue)
            // Each change the page showed, against the gateway's publication of that state just before it.
            // The first entry is the state the page found when it opened, not a change it saw happen.
            val latencies = changes.drop(1).flatMap { case (state, at) =>
              published.filter { case (st, t) => st == state && t <= at && at - t < 5000 }.lastOption.map(at - _._2)
            }.sorted
            progress(s"${latencies.size} game-state changes seen on the page: ${latencies.mkString(", ")} ms")
            ListMap(
              "web_idle_cpu_pct_without" -> without,
              "web_idle_cpu_pct" -> cpu,
              "web_heap_growth_mb" -> (heapAfter - heapBefore) / 1e6,
              "web_change_latency_ms_p50" -> Try(latencies(latencies.size / 2).toDouble).getOrElse(Double.NaN),
              "web_change_latency_ms_max" -> latencies.lastOption.fold(Double.NaN)(_.toDouble)
            )
          }
      }
      viewer.foreach(_.destroy())
      Try(demo.stop())
      withClients
    } finally {
      system.terminate()
      Await.ready(system.whenTerminated, 30.seconds)
    }
  }
}
