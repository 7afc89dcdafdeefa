package bench

import java.nio.charset.StandardCharsets
import java.nio.file.{Files, Paths}

import scala.collection.immutable.ListMap

/** One group of figures of the benchmark suite. */
trait Benchmark {

  /** A short name for progress lines. */
  def name: String

  /** Runs the benchmark and returns its figures, name to number. */
  def run(): ListMap[String, Double]
}

/** `./sbt bench`: runs every benchmark, prints a table and writes target/bench/results.json. */
object BenchSuite {

  /** Every benchmark, in the order they run. */
  val benchmarks: Vector[Benchmark] =
    Vector(CodecBench, StreamBench, SimBench, TimeSyncBench, GatewayBench, CallPathBench, ForgeryBench, RobotCtlBench,
      IdleCpuBench, FloodBench, WebBench, FirmwareBench)

  /** Run only when named: `./sbt "bench soak [minutes]"`. `./sbt "bench gateway:rtt,ingest"` runs those parts of the
    * gateway's.
    */
  val onRequest: Vector[Benchmark] = Vector(Soak)

  def main(args: Array[String]): Unit = {
    args.flatMap(_.toDoubleOption).headOption.foreach(m => Soak.minutes = m)
    args.collect { case s"gateway:$parts" => GatewayBench.parts = parts.split(',').toSet }
    val names = args.filter(_.toDoubleOption.isEmpty).map(_.takeWhile(_ != ':'))
    val selected = if (names.isEmpty) benchmarks else (benchmarks ++ onRequest).filter(b => names.contains(b.name))
    val results = selected.foldLeft(ListMap.empty[String, Double]) { (acc, b) =>
      println(s"running ${b.name} ...")
      acc ++ b.run()
    }
    val out = Paths.get("target", "bench", "results.json")
    Files.createDirectories(out.getParent)
    // A run of some groups keeps the figures of the others from the previous run.
    val merged = if (names.isEmpty) results else previous(out) ++ results
    Files.write(out, toJson(merged).getBytes(StandardCharsets.UTF_8))
    println(table(results))
    println(s"written to ${out.toAbsolutePath}")
  }

  private val Entry = """\s*"([^"]+)"\s*:\s*(-?[0-9.eE+-]+|null)\s*,?\s*""".r

  /** The figures of an earlier results file, if there is one. */
  def previous(file: java.nio.file.Path): ListMap[String, Double] =
    if (!Files.exists(file)) ListMap.empty
    else
      ListMap.from(new String(Files.readAllBytes(file), StandardCharsets.UTF_8).linesIterator.collect {
        case Entry(k, v) if v != "null" => k -> v.toDouble
      })

  /** A flat JSON object, figure name to number. */
  def toJson(results: ListMap[String, Double]): String =
    results.map { case (k, v) => s"""  "$k": ${number(v)}""" }.mkString("{\n", ",\n", "\n}\n")

  private def number(v: Double): String =
    if (v.isNaN || v.isInfinite) "null"
    else if (v == math.rint(v) && math.abs(v) < 1e15) v.toLong.toString
    else f"$v%.4f"

  private def table(results: ListMap[String, Double]): String = {
    val width = (results.keys.map(_.length) ++ Iterator(6)).max
    val lines = results.map { case (k, v) => s"${k.padTo(width, ' ')}  ${number(v)}" }
    (s"${"figure".padTo(width, ' ')}  value" +: lines.toSeq).mkString("\n")
  }

  /** Operations per second of `op`, after a warm-up, over about `seconds` of wall time. */
  def opsPerSecond(seconds: Double, warmupSeconds: Double = 1.0)(op: () => Int): Double = {
    var sink = 0
    def loop(limitNanos: Long): (Long, Long) = {
      val start = System.nanoTime()
      var n = 0L
      var now = start
      while (now - start < limitNanos) {
        var i = 0
        while (i < 1000) { sink += op(); i += 1 }
        n += 1000
        now = System.nanoTime()
      }
      (n, now - start)
    }
    loop((warmupSeconds * 1e9).toLong)
    val (n, nanos) = loop((seconds * 1e9).toLong)
    if (sink == 42) println("") // keeps the results alive so the JIT cannot drop the work
    n * 1e9 / nanos
  }
}
