package bench

import java.io.File
import java.net.{InetAddress, InetSocketAddress}
import java.nio.charset.StandardCharsets
import java.nio.file.{Files, Path, Paths}
import java.util.concurrent.TimeUnit

import scala.collection.immutable.ListMap
import scala.concurrent.Await
import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.util.{Random, Try}

import akka.actor.typed.ActorSystem
import akka.actor.typed.scaladsl.Behaviors
import com.typesafe.config.ConfigFactory

import naogateway.testkit.TestLoopback
import naogateway.sim.network.{Direction, Impairment, LossyNetwork}
import naogateway.sim.{Fleet, FleetSettings, SimulatedGameController, SimulatedGameControllerSettings}

/** `./sbt "bench soak [minutes]"`: the installed package's gateway for a game day in small.
  *
  * `bin/naogateway` from the staged package (`apps/target/universal/stage`, which the `bench` alias builds first) runs
  * in a JVM of its own with a config that turns its own simulated robots off. This JVM runs three simulated robots
  * (with the GS1500M and CM-530 models) behind a lossy loopback network, and the simulated GameController cycling
  * through a game. For the given minutes (default 20, past the 15-minute stop of the BSL Akka releases): every few
  * seconds `bin/robotctl` makes a call to a random robot and asks for the status; every minute one robot is
  * power-cycled; every few minutes one robot's link loses most of its datagrams for a while.
  *
  * Figures: `soak_minutes` (minutes run), `soak_alive` (1 if the gateway process lived and answered to the end),
  * `soak_heap_after_gc_growth_bytes_per_min` (least-squares slope of the gateway's used heap after a full GC, sampled
  * every minute from the third minute on), `soak_cpu_pct` (the gateway process's CPU time over the run, in percent of
  * one core), `soak_calls_unanswered` (robotctl calls that got no answer at all, neither result nor error, within 20 s:
  * goal 0), `soak_calls` (calls made), `soak_power_cycles`.
  */
object Soak extends Benchmark {
  val name = "soak"

  /** Minutes to run; `./sbt "bench soak 30"` sets it. */
  @volatile var minutes: Double = sys.env.get("NAOGATEWAY_SOAK_MINUTES").flatMap(_.toDoubleOption).getOrElse(20.0)

  private val Robots = Vector(1, 2, 3)
  private val CallEvery = 5.seconds
  private val PowerCycleEvery = 60.seconds
  private val LossBurstEvery = 4.minutes
  private val LossBurst = 20.seconds
  private val HeapEvery = 60.seconds
  private val AnswerTimeout = 20.seconds

  private def progress(line: String): Unit = println(s"  soak: $line")

  def run(): ListMap[String, Double] = {
    import Packaged.{bin, freeTcpPort, freeUdpPort}
    require(Packaged.isStaged,
      s"no package at ${Packaged.stage}: run the soak through the bench alias (./sbt \"bench soak\"), which stages it first")
    val dir = Paths.get("target", "soak").toAbsolutePath
    Files.createDirectories(dir)

    val robotPort = freeUdpPort()
    val gameControllerPort = freeUdpPort()
    val controlPort = freeTcpPort()
    val clusterPort = freeTcpPort()
    val conf = dir.resolve("soak.conf")
    Files.write(conf,
      soakConfig(robotPort, gameControllerPort, controlPort, clusterPort).getBytes(StandardCharsets.UTF_8))

    val gatewayLog = dir.resolve("naogateway.out").toFile
    val builder = new ProcessBuilder(bin("naogateway").toString, conf.toString)
      .redirectErrorStream(true).redirectOutput(gatewayLog).redirectInput(
        ProcessBuilder.Redirect.from(new File("/dev/null")))
    builder.environment().put("NAOGATEWAY_LOG_FILE", dir.resolve("naogateway.log").toString)
    builder.environment().put("NAOGATEWAY_CONTROL", s"127.0.0.1:$controlPort")
    val gateway = builder.start()
    val pid = gateway.pid()
    progress(s"bin/naogateway started (pid $pid), log in $dir")

    implicit val system: ActorSystem[Nothing] =
      ActorSystem[Nothing](Behaviors.empty, "soak",
        ConfigFactory.parseString("akka.loglevel = WARNING").withFallback(ConfigFactory.load()))
    val network = LossyNetwork.start(seed = 30)
    val random = new Random(30)
    val robotAddress = new InetSocketAddress(InetAddress.getLoopbackAddress, robotPort)
    val gameControllerAddress = new InetSocketAddress(InetAddress.getLoopbackAddress, gameControllerPort)
    try {
      val proxies = Robots.map(id => id -> network.addProxy(robotAddress, TestLoopback.address())).toMap
      val fleet = Await.result(
        Fleet.start(
          system,
          FleetSettings(robotAddress, Robots, firstAddress = TestLoopback.block(Robots.size),
            customize = s => s.copy(gateway = proxies(s.firmware.robotId).clientSide))
        ),
        60.seconds
      )
      val gameController = ActorSystem(
        SimulatedGameController(SimulatedGameControllerSettings(gameControllerAddress)),
        "soak-gc",
        ConfigFactory.parseString("akka.loglevel = WARNING").withFallback(ConfigFactory.load())
      )

      def robotctl(args: String*): Either[String, String] = {
        val b = new ProcessBuilder((bin("robotctl").toString +: args).asJava).redirectErrorStream(true)
        b.environment().put("NAOGATEWAY_CONTROL", s"127.0.0.1:$controlPort")
        val p = b.start()
        val out = p.getInputStream
        if (!p.waitFor(AnswerTimeout.toSeconds, TimeUnit.SECONDS)) { p.destroyForcibly(); Left("no answer") }
        else {
          val text = new String(out.readAllBytes(), StandardCharsets.UTF_8)
          if (p.exitValue() == 0 || p.exitValue() == 1) Right(text) else Left(s"exit ${p.exitValue()}: $text")
        }
      }

      // Until the three robots are online, as an operator would wait.
      val upBy = 120.seconds.fromNow
      var up = false
      while (!up && upBy.hasTimeLeft()) {
        up =
          robotctl("status").toOption.exists(_.linesIterator.count(_.split("\\s+").contains("online")) >= Robots.size)
        if (!up) Thread.sleep(1000)
      }
      require(up, s"the gateway did not report ${Robots.size} robots online within 2 minutes; see $gatewayLog")
      progress("three robots online; soaking for " + f"$minutes%.1f minutes")

      val cpuStart = Packaged.cpuNanos(pid)
      val start = System.nanoTime()
      val end = (minutes * 60).seconds.fromNow
      var nextCall, nextCycle, nextHeap = Deadline.now
      var nextBurst = Deadline.now + 90.seconds
      var burstEnds: Option[(Deadline, Int)] = None
      var calls, unanswered, powerCycles = 0
      val heap = Vector.newBuilder[(Double, Double)]
      var alive = true
      while (alive && end.hasTimeLeft()) {
        if (nextCall.isOverdue()) {
          val id = Robots(random.nextInt(Robots.size))
          calls += 1
          robotctl("call", id.toString, "motion", "getPosture") match {
            case Left(why) =>
              unanswered += 1
              progress(s"call to robot $id unanswered: $why")
            case Right(_) => ()
          }
          robotctl("status") match {
            case Left(why) => progress(s"status unanswered: $why")
            case Right(_)  => ()
          }
          nextCall = CallEvery.fromNow
        }
        if (nextCycle.isOverdue() && System.nanoTime() - start > 30e9) {
          val id = Robots(random.nextInt(Robots.size))
          Try(Await.result(fleet.powerCycle(id), 30.seconds)).fold(e => progress(s"power cycle of $id failed: $e"),
            _ => powerCycles += 1)
          nextCycle = PowerCycleEvery.fromNow
        }
        if (nextBurst.isOverdue() && burstEnds.isEmpty) {
          val id = Robots(random.nextInt(Robots.size))
          val lossy = Impairment(loss = 0.6)
          network.setImpairment(proxies(id), Direction.Uplink, lossy)
          network.setImpairment(proxies(id), Direction.Downlink, lossy)
          burstEnds = Some((LossBurst.fromNow, id))
          progress(s"loss burst on robot $id for ${LossBurst.toSeconds} s")
        }
        burstEnds.filter(_._1.isOverdue()).foreach { case (_, id) =>
          network.setImpairment(proxies(id), Direction.Uplink, Impairment.Off)
          network.setImpairment(proxies(id), Direction.Downlink, Impairment.Off)
          burstEnds = None
          nextBurst = LossBurstEvery.fromNow
        }
        if (nextHeap.isOverdue()) {
          val minute = (System.nanoTime() - start) / 60e9
          heapAfterGc(pid).foreach { bytes =>
            heap += minute -> bytes.toDouble
            progress(
              f"minute $minute%.1f: heap after GC ${bytes / 1e6}%.1f MB, $calls calls, $unanswered unanswered, $powerCycles power cycles")
          }
          nextHeap = HeapEvery.fromNow
        }
        alive = gateway.isAlive
        Thread.sleep(200)
      }
      val ranMinutes = (System.nanoTime() - start) / 60e9
      val cpuPct = (for (a <- cpuStart; b <- Packaged.cpuNanos(pid))
        yield (b - a) / (ranMinutes * 60e9) * 100).getOrElse(Double.NaN)
      alive = alive && gateway.isAlive && robotctl("status").isRight
      gameController.terminate()
      Try(Await.result(fleet.stop(), 30.seconds))
      val samples = heap.result().filter(_._1 >= 2.0)
      ListMap(
        "soak_minutes" -> ranMinutes,
        "soak_alive" -> (if (alive) 1.0 else 0.0),
        "soak_heap_after_gc_growth_bytes_per_min" -> slope(samples),
        "soak_cpu_pct" -> cpuPct,
        "soak_calls_unanswered" -> unanswered.toDouble,
        "soak_calls" -> calls.toDouble,
        "soak_power_cycles" -> powerCycles.toDouble
      )
    } finally {
      network.stop()
      system.terminate()
      Try(Await.result(system.whenTerminated, 30.seconds))
      gateway.destroy()
      if (!gateway.waitFor(30, TimeUnit.SECONDS)) gateway.destroyForcibly()
      progress(s"gateway stopped (exit ${Try(gateway.exitValue()).getOrElse(-1)})")
    }
  }

  private def soakConfig(robotPort: Int, gameControllerPort: Int, controlPort: Int, clusterPort: Int): String =
    s"""# Written by the soak: the package's gateway without its own simulated robots, on loopback.
       |apps.launcher { simulated-robots = 0, ball-follower-robot = 0, game-controller = off }
       |apps.zeromq.enabled = off
       |apps.datagram-door.enabled = off
       |apps.control.bind = "127.0.0.1:$controlPort"
       |naogateway.link { bind-address = "127.0.0.1", robot-port = $robotPort }
       |naogateway.game-controller { bind-address = "127.0.0.1", port = $gameControllerPort }
       |robotmiddleware.cluster { gateway-host = "127.0.0.1", gateway-port = $clusterPort }
       |""".stripMargin

  private lazy val jcmd: Path = {
    val java = Paths.get(ProcessHandle.current().info().command().orElse("java"))
    Option(java.getParent).map(_.resolve("jcmd")).filter(Files.isExecutable(_)).getOrElse(Paths.get("jcmd"))
  }

  private def jcmdOut(pid: Long, command: String*): String = {
    val p = new ProcessBuilder((Seq(jcmd.toString, pid.toString) ++ command).asJava).redirectErrorStream(true).start()
    val text = new String(p.getInputStream.readAllBytes(), StandardCharsets.UTF_8)
    p.waitFor(30, TimeUnit.SECONDS)
    text
  }

  private val Used = """used (\d+)K""".r.unanchored

  /** The gateway's used heap right after a full GC, in bytes. */
  private def heapAfterGc(pid: Long): Option[Long] = {
    jcmdOut(pid, "GC.run")
    jcmdOut(pid, "GC.heap_info") match {
      case Used(k) => Some(k.toLong * 1024)
      case other =>
        progress(s"jcmd GC.heap_info said: ${other.take(200)}")
        None
    }
  }

  /** Least-squares slope of y over x; 0 with fewer than two samples. */
  def slope(samples: Seq[(Double, Double)]): Double =
    if (samples.size < 2) 0.0
    else {
      val n = samples.size.toDouble
      val mx = samples.map(_._1).sum / n
      val my = samples.map(_._2).sum / n
      val sxx = samples.map { case (x, _) => (x - mx) * (x - mx) }.sum
      if (sxx == 0) 0.0 else samples.map { case (x, y) => (x - mx) * (y - my) }.sum / sxx
    }
}
