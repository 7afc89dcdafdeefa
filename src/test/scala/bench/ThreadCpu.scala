package bench

import java.nio.charset.StandardCharsets
import java.nio.file.{Files, Path, Paths}

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.sys.process._
import scala.util.Try

/** Where a process's CPU goes and how often its threads wake, per thread group, from `/proc/<pid>/task/<tid>/`: CPU
  * time (utime + stime) and voluntary context switches (a thread that blocked and was woken again: timers, polls, pools
  * waking a worker). Wake-ups are what idle costs, and unlike CPU % a shared machine's load hardly moves them. Thread
  * names come from the JVM's own thread dump (`jcmd <pid> Thread.print`: the kernel keeps only 15 characters of a
  * name), grouped without their numbers (`robots-akka.actor.default-dispatcher-3` is one of
  * `robots-akka.actor.default-dispatcher`). Linux only: elsewhere a window is empty.
  */
object ThreadCpu {

  /** One group's figures over a window: threads, % of one core, voluntary and involuntary switches a second. */
  final case class Group(name: String, threads: Int, cpuPct: Double, wakeUpsPerSecond: Double,
      preemptedPerSecond: Double)

  private final case class Sample(name: String, ticks: Long, voluntary: Long, involuntary: Long)

  // Clock ticks a second of /proc's utime and stime; 100 on every Linux the project runs on.
  private val TicksPerSecond = 100.0

  /** The groups of process `pid` over `window` (most CPU first), measured while the caller sleeps. */
  def window(pid: Long, window: FiniteDuration): Vector[Group] = {
    val names = jvmThreadNames(pid)
    val before = sample(pid, names)
    val start = System.nanoTime()
    Thread.sleep(window.toMillis)
    val after = sample(pid, names ++ jvmThreadNames(pid))
    val seconds = (System.nanoTime() - start) / 1e9
    after.toVector.groupBy { case (_, s) => group(s.name) }.map { case (name, threads) =>
      def delta(f: Sample => Long) =
        threads.map { case (tid, s) => f(s) - before.get(tid).fold(0L)(f) }.sum.toDouble
      Group(name, threads.size, delta(_.ticks) * 100 / TicksPerSecond / seconds, delta(_.voluntary) / seconds,
        delta(_.involuntary) / seconds)
    }.toVector.sortBy(g => (-g.cpuPct, -g.wakeUpsPerSecond))
  }

  /** The groups as table lines (those with any CPU or wake-up), and a total line. */
  def lines(groups: Vector[Group]): Vector[String] = {
    val shown = groups.filter(g => g.cpuPct > 0.005 || g.wakeUpsPerSecond >= 0.5)
    val total = Group("total", groups.map(_.threads).sum, groups.map(_.cpuPct).sum,
      groups.map(_.wakeUpsPerSecond).sum, groups.map(_.preemptedPerSecond).sum)
    f"${"threads"}%-46s ${"n"}%3s ${"cpu %"}%7s ${"wakes/s"}%8s ${"preempt/s"}%9s" +:
      (shown :+ total).map(g =>
        f"${g.name.take(46)}%-46s ${g.threads}%3d ${g.cpuPct}%7.2f ${g.wakeUpsPerSecond}%8.1f ${g.preemptedPerSecond}%9.1f")
  }

  /** A thread's group: its name without the pool's thread number. */
  private[bench] def group(name: String): String = name.replaceAll("[-#]?\\d+$", "")

  private def sample(pid: Long, names: Map[String, String]): Map[String, Sample] = {
    val tasks = Paths.get("/proc", pid.toString, "task")
    Try(Files.list(tasks).iterator().asScala.toVector).getOrElse(Vector.empty).flatMap { dir =>
      val tid = dir.getFileName.toString
      Try {
        val stat = read(dir.resolve("stat"))
        val comm = stat.substring(stat.indexOf('(') + 1, stat.lastIndexOf(')'))
        val fields = stat.substring(stat.lastIndexOf(')') + 2).split(' ')
        val status = read(dir.resolve("status")).linesIterator.toVector
        def switches(key: String) =
          status.find(_.startsWith(key)).map(_.split("\\s+").last.toLong).getOrElse(0L)
        tid -> Sample(names.getOrElse(tid, comm), fields(11).toLong + fields(12).toLong,
          switches("voluntary_ctxt_switches:"), switches("nonvoluntary_ctxt_switches:"))
      }.toOption
    }.toMap
  }

  private def read(p: Path): String = new String(Files.readAllBytes(p), StandardCharsets.UTF_8)

  // The JVM's thread names by native thread id (`nid=0x…` in a thread dump), or none when jcmd cannot say.
  private def jvmThreadNames(pid: Long): Map[String, String] = {
    val jcmd = Paths.get(System.getProperty("java.home"), "bin", "jcmd")
    if (!Files.isExecutable(jcmd)) Map.empty
    else {
      val dump = Try(Seq(jcmd.toString, pid.toString, "Thread.print").!!(ProcessLogger(_ => ()))).getOrElse("")
      val line = "^\"([^\"]*)\".*?nid=0x([0-9a-f]+).*$".r
      dump.linesIterator.collect { case line(name, nid) => java.lang.Long.parseLong(nid, 16).toString -> name }.toMap
    }
  }
}
