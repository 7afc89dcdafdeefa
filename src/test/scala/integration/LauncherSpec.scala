package integration

import java.io.{BufferedReader, InputStreamReader}
import java.net.ServerSocket
import java.util.concurrent.{LinkedBlockingQueue, TimeUnit}

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** `./sbt run` as a user sees it: a separate JVM running the launcher, its plain output, and Ctrl-C. */
class LauncherSpec extends AnyWordSpec with Matchers {

  private def freePort(): Int = { val s = new ServerSocket(0); try s.getLocalPort finally s.close() }

  "The launcher" should {
    "start, show three robots online, and exit cleanly on SIGINT" in {
      assume(new java.io.File("/bin/kill").exists || new java.io.File("/usr/bin/kill").exists, "no kill command to send SIGINT")
      val javaBin = s"${System.getProperty("java.home")}/bin/java"
      val command = Seq(javaBin, "-Xmx768m", "-cp", System.getProperty("java.class.path"), "apps.Launcher")
      // A process started in the background of a non-interactive shell inherits SIGINT as ignored, and the JVM then
      // never installs its handler; python resets it to the default first, as an interactive terminal would have it.
      val python = Seq("python3", "-c", "import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); os.execv(sys.argv[1], sys.argv[1:])")
      val hasPython = scala.util.Try(new ProcessBuilder("python3", "--version").start().waitFor() == 0).getOrElse(false)
      assume(hasPython, "python3 is needed to give the launcher a default SIGINT disposition")
      val builder = new ProcessBuilder((python ++ command).asJava).redirectErrorStream(true)
      builder.environment().put("ROBOTS_GATEWAY_PORT", freePort().toString)
      builder.environment().put("NAOGATEWAY_ZEROMQ_BIND", s"tcp://127.0.0.1:${freePort()}")
      builder.environment().put("NAOGATEWAY_ZEROMQ_PUBLISH", s"tcp://127.0.0.1:${freePort()}")
      builder.environment().put("NAOGATEWAY_LOG_FILE", "target/launcher-spec.log")
      val process = builder.start()
      val lines = new LinkedBlockingQueue[String]()
      val reader = new Thread(() => {
        val in = new BufferedReader(new InputStreamReader(process.getInputStream))
        Iterator.continually(in.readLine()).takeWhile(_ != null).foreach(lines.put)
      })
      reader.setDaemon(true)
      reader.start()
      try {
        val seen = scala.collection.mutable.ArrayBuffer.empty[String]
        val deadline = 90.seconds.fromNow
        def online = seen.filter(l => l.startsWith("robot ") && l.contains(" online ")).map(_.split("\\s+")(1)).toSet
        while (online.size < 3 && deadline.hasTimeLeft()) {
          Option(lines.poll(1, TimeUnit.SECONDS)).foreach(seen += _)
        }
        withClue(seen.mkString("\n")) { online shouldBe Set("1", "2", "3") }

        val signalled = System.nanoTime()
        new ProcessBuilder("kill", "-INT", process.pid().toString).start().waitFor()
        process.waitFor(30, TimeUnit.SECONDS) shouldBe true
        val took = (System.nanoTime() - signalled).nanos
        reader.join(5000)
        lines.drainTo(seen.asJava)
        withClue(seen.takeRight(10).mkString("\n")) { seen.exists(_.contains("naogateway stopped")) shouldBe true }
        // The goal is 2 s; a loaded CI machine gets a generous margin here, the figure is in the benchmark notes.
        took should be < 15.seconds
        info(s"shut down ${took.toMillis} ms after SIGINT")
      } finally if (process.isAlive) process.destroyForcibly()
    }
  }
}
