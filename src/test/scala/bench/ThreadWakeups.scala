package bench

import java.nio.charset.StandardCharsets
import java.nio.file.{Files, Path, Paths}

import scala.jdk.CollectionConverters._
import scala.util.Try

/** The context switches of this JVM's threads, from /proc/self/task/<tid>/status: a thread that blocks and is woken
  * again counts one voluntary switch, so switches per call count the wake-ups a call costs, which load does not move.
  * Empty where /proc is not there.
  */
private[bench] object ThreadWakeups {

  /** One thread's counters: its name as the kernel knows it (15 characters at most), its voluntary and involuntary
    * switches, its CPU time (user + system) in clock ticks.
    */
  final case class Counts(name: String, voluntary: Long, involuntary: Long, cpuTicks: Long)

  /** Every thread of process `pid` (this JVM's by default) now, by thread id. */
  def snapshot(pid: String = "self"): Map[Long, Counts] = {
    val tasks = Paths.get(s"/proc/$pid/task")
    if (!Files.isDirectory(tasks)) Map.empty
    else {
      val dirs = Files.list(tasks)
      try dirs.iterator().asScala.toVector.flatMap(read).toMap
      finally dirs.close()
    }
  }

  private def read(dir: Path): Option[(Long, Counts)] = Try {
    val lines = new String(Files.readAllBytes(dir.resolve("status")), StandardCharsets.US_ASCII).linesIterator
    val fields = lines.map(_.split(":\\s*", 2)).collect { case Array(k, v) => k -> v.trim }.toMap
    // stat: the name in parentheses, then fields 3 on; utime and stime are fields 14 and 15.
    val stat = new String(Files.readAllBytes(dir.resolve("stat")), StandardCharsets.US_ASCII)
    val rest = stat.substring(stat.lastIndexOf(')') + 2).split(' ')
    dir.getFileName.toString.toLong ->
      Counts(fields("Name"), fields("voluntary_ctxt_switches").toLong, fields("nonvoluntary_ctxt_switches").toLong,
        rest(11).toLong + rest(12).toLong)
  }.toOption

  /** Voluntary switches per call between `before` and `after` over `calls` calls: all threads together, and the threads
    * that woke at least once every ten calls, by name, busiest first.
    */
  def perCall(before: Map[Long, Counts], after: Map[Long, Counts], calls: Int): (Double, Vector[(String, Double)]) = {
    val deltas = after.toVector.map { case (tid, a) =>
      val b = before.get(tid).map(_.voluntary).getOrElse(0L)
      s"${a.name}#$tid" -> (a.voluntary - b).toDouble / calls
    }
    (deltas.map(_._2).sum, deltas.filter(_._2 >= 0.1).sortBy(-_._2))
  }
}
