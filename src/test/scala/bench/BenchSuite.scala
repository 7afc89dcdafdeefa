package bench

import java.nio.charset.StandardCharsets
import java.nio.file.{Files, Paths}

import java.lang.management.ManagementFactory

import scala.collection.immutable.ListMap
import scala.jdk.CollectionConverters._

/** One group of figures of the benchmark suite. */
trait Benchmark {

  /** A short name for progress lines. */
  def name: String

  /** Runs the benchmark and returns its figures, name to number. */
  def run(): ListMap[String, Double]

  /** Whether its figures move with the machine's load (latencies, throughputs, CPU shares): the suite runs it twice and
    * keeps the run the machine was quieter for.
    */
  def quietSensitive: Boolean = false

  /** Options of the JVM each of its runs gets (a load-sensitive group's runs have a JVM of their own), after the
    * suite's own.
    */
  def jvmOptions: Seq[String] = Nil
}

/** Each ratio of the suite with the two figures it divides (the measured one, then its floor), and a judgement of the
  * machine's load: what the table prints beside the figures.
  */
object BenchRatios {

  /** Ratio figure -> (measured figure, floor figure). A ratio the suite computes itself is in [[derived]]. */
  val floors: ListMap[String, (String, String)] = ListMap(
    "ingest_over_raw_udp" -> ("ingest_datagrams_s", "raw_udp_ingest_datagrams_s"),
    "recording_ingest_ratio" -> ("recording_ingest_datagrams_s", "ingest_without_recording_datagrams_s"),
    "rpc_rtt_over_raw_udp_p50" -> ("rpc_rtt_p50_us", "raw_udp_rtt_p50_us"),
    "codec_status_decode_over_floor" -> ("codec_status_decode_ops_s", "codec_status_decode_baseline_ops_s"),
    "callpath_gateway_over_raw_udp_p50" -> ("callpath_gateway_p50_us", "callpath_raw_udp_p50_us"),
    "callpath_gateway_signed_over_gateway_p50" -> ("callpath_gateway_signed_p50_us", "callpath_gateway_p50_us"),
    "callpath_interface_over_gateway_p50" -> ("callpath_interface_p50_us", "callpath_gateway_p50_us"),
    "callpath_cluster_over_gateway_p50" -> ("callpath_cluster_p50_us", "callpath_gateway_p50_us"),
    "callpath_python_over_mavsdk_p50" -> ("callpath_python_p50_us", "callpath_mavsdk_p50_us"),
    "callpath_python_datagram_over_mavsdk_p50" -> ("callpath_python_datagram_p50_us", "callpath_mavsdk_p50_us"),
    "callpath_zeromq_floor_over_mavsdk_p50" -> ("callpath_zeromq_floor_p50_us", "callpath_mavsdk_p50_us"),
    "callpath_python_over_mavsdk_grpc_p50" -> ("callpath_python_p50_us", "callpath_mavsdk_grpc_p50_us"),
    "bus_bridge_over_direct_p50" -> ("bus_bridge_ping_p50_us", "bus_direct_ping_p50_us")
  )

  /** The ratios of [[floors]] that no benchmark computes, from `results` (where both figures are there). */
  def derived(results: ListMap[String, Double]): ListMap[String, Double] =
    ListMap.from(Seq("ingest_over_raw_udp", "rpc_rtt_over_raw_udp_p50", "codec_status_decode_over_floor").flatMap {
      ratio =>
        val (measured, floor) = floors(ratio)
        for (m <- results.get(measured); f <- results.get(floor) if !results.contains(ratio)) yield ratio -> m / f
    })

  /** A run is too loaded to judge a quiet-machine goal when the one-minute load average exceeded the cores (other work
    * then competes for every core the figure needs).
    */
  def tooLoaded(load: Double, cores: Int): Boolean = load > cores

  /** The one-minute load average, NaN where the system does not say. */
  def load1(): Double = ManagementFactory.getOperatingSystemMXBean.getSystemLoadAverage match {
    case l if l < 0 => Double.NaN
    case l          => l
  }
}

/** `./sbt bench`: runs every benchmark, prints a table and writes target/bench/results.json. */
object BenchSuite {

  /** Every benchmark, in the order they run. */
  val benchmarks: Vector[Benchmark] =
    Vector(
      CodecBench,
      StreamBench,
      SimBench,
      TimeSyncBench,
      GatewayBench,
      CallPathBench,
      ForgeryBench,
      RobotCtlBench,
      IdleCpuBench,
      FloodBench,
      WebBench,
      BusBench,
      FirmwareBench,
      FollowerBench
    )

  /** Run only when named: `./sbt "bench soak [minutes]"`. `./sbt "bench gateway:rtt,ingest"` runs those parts of the
    * gateway's; `callpath:quick` and `callpath:demo` the port loop's parts of the call path's (`CallPathBench.parts`).
    */
  val onRequest: Vector[Benchmark] = Vector(Soak)

  /** The argument that makes this JVM one run of one group for a parent suite: `--one NAME FILE ARGS…`. */
  private val One = "--one"

  def main(args: Array[String]): Unit = args.toSeq match {
    case Seq(One, name, file, rest @ _*) =>
      configure(rest)
      val b = (benchmarks ++ onRequest).find(_.name == name).getOrElse(sys.error(s"no benchmark $name"))
      Files.write(Paths.get(file), toJson(b.run()).getBytes(StandardCharsets.UTF_8))
      // Akka's and the drivers' non-daemon threads must not keep the run's JVM alive.
      sys.exit(0)
    case _ => suite(args.toSeq)
  }

  // The groups' settings the arguments carry (the parent passes them on to each run's JVM).
  private def configure(args: Seq[String]): Unit = {
    args.flatMap(_.toDoubleOption).headOption.foreach(m => Soak.minutes = m)
    args.collect { case s"gateway:$parts" => GatewayBench.parts = parts.split(',').toSet }
    args.collect { case s"callpath:$parts" => CallPathBench.parts = parts.split(',').toSet }
  }

  /** One run of group `b` in a JVM of its own, with this JVM's options, the group's and this class path; its figures.
    */
  private def forked(b: Benchmark, args: Seq[String]): ListMap[String, Double] = {
    val name = b.name
    val file = Files.createTempFile("bench-run-", ".json")
    try {
      val java = Paths.get(System.getProperty("java.home"), "bin", "java").toString
      val options = ManagementFactory.getRuntimeMXBean.getInputArguments.asScala.toSeq ++ b.jvmOptions
      val command = (java +: options) ++ Seq("-cp", System.getProperty("java.class.path"), "bench.BenchSuite", One,
        name, file.toString) ++ args
      val exit = new ProcessBuilder(command: _*).inheritIO().start().waitFor()
      if (exit != 0) sys.error(s"the JVM of the $name run exited with $exit")
      previous(file, unmeasured = true)
    } finally Files.deleteIfExists(file)
  }

  private def suite(args: Seq[String]): Unit = {
    configure(args)
    val names = args.filter(_.toDoubleOption.isEmpty).map(_.takeWhile(_ != ':'))
    val selected = if (names.isEmpty) benchmarks else (benchmarks ++ onRequest).filter(b => names.contains(b.name))
    val cores = Runtime.getRuntime.availableProcessors
    val results = selected.foldLeft(ListMap.empty[String, Double]) { (acc, b) =>
      // A figure a quiet machine changes is taken twice, each time in a JVM of its own (as JMH forks one per
      // benchmark): in one JVM the second run found the code the first run and the groups before had compiled, for
      // other callers and other shapes of input (the status decode measured 0.83 of its floor in the first run, 0.72
      // in the second). The run with the lower load average is kept, both printed.
      val runs = (1 to (if (b.quietSensitive) 2 else 1)).map { i =>
        println(s"running ${b.name}${if (b.quietSensitive) s" (run $i of 2)" else ""} ... load average ${load(cores)}")
        val before = BenchRatios.load1()
        val figures = if (b.quietSensitive) forked(b, args) else b.run()
        val during = (before + BenchRatios.load1()) / 2
        println(f"${b.name} run $i: load average $during%.2f over $cores cores" +
          (if (BenchRatios.tooLoaded(during, cores)) ": too loaded to judge the goals of a quiet machine" else ""))
        (figures, during)
      }
      if (runs.size > 1) runs.zipWithIndex.foreach { case ((figures, l), i) =>
        println(f"${b.name} run ${i + 1} (load average $l%.2f): " +
          figures.map { case (k, v) => s"$k ${number(v)}" }.mkString(", "))
      }
      val (kept, load1) = runs.minBy(r => if (r._2.isNaN) Double.MaxValue else r._2)
      acc ++ kept + (s"${b.name}_load_avg" -> load1)
    }
    val withRatios = results ++ BenchRatios.derived(results)
    val out = Paths.get("target", "bench", "results.json")
    Files.createDirectories(out.getParent)
    // A run of some groups keeps the figures of the others from the previous run.
    val merged = if (names.isEmpty) withRatios else previous(out) ++ withRatios
    Files.write(out, toJson(merged).getBytes(StandardCharsets.UTF_8))
    val loads = selected.flatMap(b => withRatios.get(s"${b.name}_load_avg").map(b.name -> _)).toMap
    println(table(withRatios, loads))
    println(s"written to ${out.toAbsolutePath}")
  }

  private val Entry = """\s*"([^"]+)"\s*:\s*(-?[0-9.eE+-]+|null)\s*,?\s*""".r

  /** The figures of an earlier results file, if there is one; `unmeasured` keeps those it has none for (null) as NaN.
    */
  def previous(file: java.nio.file.Path, unmeasured: Boolean = false): ListMap[String, Double] =
    if (!Files.exists(file)) ListMap.empty
    else
      ListMap.from(new String(Files.readAllBytes(file), StandardCharsets.UTF_8).linesIterator.collect {
        case Entry(k, v) if v != "null" => k -> v.toDouble
        case Entry(k, _) if unmeasured  => k -> Double.NaN
      })

  /** A flat JSON object, figure name to number. */
  def toJson(results: ListMap[String, Double]): String =
    results.map { case (k, v) => s"""  "$k": ${number(v)}""" }.mkString("{\n", ",\n", "\n}\n")

  private def number(v: Double): String =
    if (v.isNaN || v.isInfinite) "null"
    else if (v == math.rint(v) && math.abs(v) < 1e15) v.toLong.toString
    else f"$v%.4f"

  private def load(cores: Int): String = f"${BenchRatios.load1()}%.2f (${cores} cores)"

  /** The figures, one a line; a ratio with the two figures it divides, and a warning where its group's run was too
    * loaded to judge (`loads`: group name to its load average).
    */
  private def table(results: ListMap[String, Double], loads: Map[String, Double]): String = {
    val cores = Runtime.getRuntime.availableProcessors
    val loaded = loads.filter { case (_, l) => BenchRatios.tooLoaded(l, cores) }
    val width = (results.keys.map(_.length) ++ Iterator(6)).max
    val lines = results.map { case (k, v) =>
      val beside = BenchRatios.floors.get(k).map { case (m, f) =>
        s"   = $m ${results.get(m).fold("?")(number)} / $f ${results.get(f).fold("?")(number)}"
      }.getOrElse("")
      s"${k.padTo(width, ' ')}  ${number(v).padTo(10, ' ')}$beside"
    }
    val notes = loaded.toSeq.sortBy(_._1).map { case (g, l) =>
      f"NOTE: the $g figures were taken at load average $l%.2f on $cores cores: too loaded to judge against the goals"
    }
    ((s"${"figure".padTo(width, ' ')}  value" +: lines.toSeq) ++ notes).mkString("\n")
  }

  /** Operations per second of `op`, after a warm-up, over about `seconds` of wall time. */
  def opsPerSecond(seconds: Double, warmupSeconds: Double = 1.0)(op: () => Int): Double = {
    batches(op, (warmupSeconds * 1e9).toLong)
    val (n, nanos) = batches(op, (seconds * 1e9).toLong)
    n * 1e9 / nanos
  }

  /** Runs `op` in batches of 1000 for about `limitNanos`: the operations run and the nanoseconds they took. */
  private[bench] def batches(op: () => Int, limitNanos: Long): (Long, Long) = {
    var sink = 0
    val start = System.nanoTime()
    var n = 0L
    var now = start
    while (now - start < limitNanos) {
      var i = 0
      while (i < 1000) { sink += op(); i += 1 }
      n += 1000
      now = System.nanoTime()
    }
    results = sink // keeps the results alive so the JIT cannot drop the work
    (n, now - start)
  }
  @volatile private[bench] var results = 0
}
