package endtoend

import java.io.{BufferedReader, InputStreamReader}
import java.net.{DatagramSocket, ServerSocket}
import java.nio.charset.StandardCharsets
import java.nio.file.{Files, Path, Paths}
import java.util.concurrent.{ConcurrentLinkedQueue, LinkedBlockingQueue, TimeUnit}

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.testkit.TempFiles

/** A newcomer's path through README.md ("Your first app") and docs/writing-apps.md, in a clone of this repository's
  * HEAD: `./sbt publishLocal` (into an ivy home of its own), the template copied to a folder of its own, and its `./sbt
  * run` against the demo, which must walk robot 2 (robotctl's watch sees it walking), end with the app's line, exit 0,
  * and print no SLF4J warning and no dead letter; without a gateway the app says where it looked. Two sbt builds from
  * scratch take minutes, so it is not part of `./sbt test`: `./sbt firstApp` runs it (.ci/run does).
  */
class FirstAppSpec extends AnyWordSpec with Matchers {

  private def freePort(): Int = {
    val s = new ServerSocket(0)
    try s.getLocalPort
    finally s.close()
  }

  /** A process's lines (stdout and stderr), read on a thread of their own. */
  private final class Running(val process: Process) {
    val lines = new LinkedBlockingQueue[String]()
    private val reader = new Thread(() => {
      val in = new BufferedReader(new InputStreamReader(process.getInputStream, StandardCharsets.UTF_8))
      // A destroyed process closes its stream under the reader: that is its end, not an error.
      try Iterator.continually(in.readLine()).takeWhile(_ != null).foreach(lines.put)
      catch { case _: java.io.IOException => () }
    })
    reader.setDaemon(true)
    reader.start()

    /** Every line until the process exits (within `within`), and its exit code (None if it did not). */
    def toEnd(within: FiniteDuration): (Vector[String], Option[Int]) = {
      val exited = process.waitFor(within.toSeconds, TimeUnit.SECONDS)
      if (!exited) process.descendants().forEach(p => { p.destroyForcibly(); () })
      if (!exited) process.destroyForcibly()
      reader.join(10000)
      val got = new java.util.ArrayList[String]()
      lines.drainTo(got)
      (got.asScala.toVector, if (exited) Some(process.exitValue()) else None)
    }
  }

  private def start(command: Seq[String], dir: Path, env: Map[String, String]): Running = {
    val builder = new ProcessBuilder(command.asJava).directory(dir.toFile).redirectErrorStream(true)
    env.foreach { case (k, v) => builder.environment().put(k, v) }
    new Running(builder.start())
  }

  private def timed[T](f: => T): (T, FiniteDuration) = {
    val t0 = System.nanoTime()
    val r = f
    (r, (System.nanoTime() - t0).nanos)
  }

  "A team's first app, from a clone" should {
    "publish the libraries, build the template against them, walk robot 2 of the demo, and exit cleanly" in {
      val repo = Paths.get("").toAbsolutePath
      assume(Files.exists(repo.resolve(".git")), s"$repo is not a git checkout to clone")
      val work = Files.createTempDirectory("first-app")
      val demoLog = work.resolve("demo.log")
      try {
        val clone = work.resolve("naogateway")
        start(Seq("git", "clone", "-q", repo.toString, clone.toString), work, Map.empty).toEnd(5.minutes)._2 shouldBe
          Some(0)
        // Every sbt of this spec publishes to and resolves from this ivy home, not the user's.
        val ivy = work.resolve("ivy")
        val sbtEnv = Map("JAVA_TOOL_OPTIONS" -> s"-Dsbt.ivy.home=$ivy", "CI" -> "1")

        // README: ./sbt publishLocal
        val ((publishOut, publishExit), publishTook) =
          timed(start(Seq("./sbt", "publishLocal"), clone, sbtEnv).toEnd(60.minutes))
        withClue(publishOut.takeRight(40).mkString("\n"))(publishExit shouldBe Some(0))
        val published = ivy.resolve("local").resolve("org.naogateway")
        Files.list(published).iterator.asScala.map(_.getFileName.toString).toSet shouldBe Set("naogateway-proto_2.13",
          "naogateway-wire_2.13", "naogateway-api_2.13", "naogateway-access_2.13", "robotmiddleware_2.13")
        val versions = Files.list(published.resolve("robotmiddleware_2.13")).iterator.asScala.toVector
        versions should have size 1
        val version = versions.head.getFileName.toString

        // README: cp -r examples/first-app ~/robot-app; writing-apps.md: its build.sbt names the version published.
        val app = work.resolve("robot-app")
        start(Seq("cp", "-r", clone.resolve("examples/first-app").toString, app.toString), work, Map.empty).toEnd(
          1.minute)._2 shouldBe Some(0)
        val build = app.resolve("build.sbt")
        val named = "(?m)^val naogatewayVersion = \"([^\"]+)\"$".r
        val buildText = new String(Files.readAllBytes(build), StandardCharsets.UTF_8)
        named.findFirstMatchIn(buildText) shouldBe defined
        Files.write(build,
          named.replaceAllIn(buildText, s"""val naogatewayVersion = "$version"""")
            .getBytes(StandardCharsets.UTF_8))

        // README: ./sbt run (the demo), here the launcher of this build on ports of its own.
        val clusterPort = freePort()
        val controlPort = freePort()
        val gameControllerPort = {
          val s = new DatagramSocket(0);
          try s.getLocalPort
          finally s.close()
        }
        val demo = start(
          Seq(s"${System.getProperty("java.home")}/bin/java", "-Xmx768m", "-cp", System.getProperty("java.class.path"),
            "naogateway.launcher.Launcher"),
          repo,
          Map(
            "ROBOTS_GATEWAY_PORT" -> clusterPort.toString,
            "NAOGATEWAY_CONTROL" -> s"127.0.0.1:$controlPort",
            "NAOGATEWAY_GAMECONTROLLER_PORT" -> gameControllerPort.toString,
            "NAOGATEWAY_ZEROMQ" -> "off",
            "NAOGATEWAY_DATAGRAM_DOOR" -> "off",
            "NAOGATEWAY_WEB" -> "off",
            "NAOGATEWAY_LOG_FILE" -> demoLog.toString
          )
        )
        val watched = new ConcurrentLinkedQueue[String]()
        try {
          val seen = Vector.newBuilder[String]
          val deadline = 3.minutes.fromNow
          def online = seen.result().count(l => l.startsWith("robot ") && l.contains(" online "))
          while (online < 3 && deadline.hasTimeLeft() && demo.process.isAlive)
            Option(demo.lines.poll(1, TimeUnit.SECONDS)).foreach(seen += _)
          withClue(seen.result().mkString("\n"))(online should be >= 3)

          // robotctl watch 2: robot 2's status lines while the app runs (reads need no lease).
          val watcher = new Thread(() => {
            naogateway.launcher.RobotCtl.run(Seq("watch", "2", "3600"),
              Map("NAOGATEWAY_CONTROL" -> s"127.0.0.1:$controlPort").get,
              watched.add(_), _ => ())
            ()
          })
          watcher.setDaemon(true)
          watcher.start()

          // README: cd ~/robot-app && ./sbt run
          val appEnv = sbtEnv + ("ROBOTS_GATEWAY_PORT" -> clusterPort.toString)
          val ((appOut, appExit), appTook) = timed(start(Seq("./sbt", "run"), app, appEnv).toEnd(30.minutes))
          withClue(appOut.mkString("\n")) {
            appOut should contain("hello-robot: robot 2 stood up, greeted, walked and stopped")
            appExit shouldBe Some(0)
            appOut.filter(_.startsWith("SLF4J")) shouldBe empty
            appOut.filter(l => l.contains("dead letter") || l.contains("was not delivered")) shouldBe empty
          }
          withClue(watched.asScala.mkString("\n")) {
            watched.asScala.exists(l => l.matches("2 .*") && l.contains(" walking ")) shouldBe true
          }
          info(s"publishLocal in the clone: ${publishTook.toSeconds} s; the template's ./sbt run, from its first " +
            s"compile to the app's exit: ${appTook.toSeconds} s; version $version")
        } finally {
          demo.process.destroy()
          demo.toEnd(30.seconds)
        }

        // Without the demo the app says where it looked and what to start.
        val (aloneOut, aloneExit) = start(Seq("./sbt", "run"), app,
          sbtEnv + ("ROBOTS_GATEWAY_PORT" ->
            clusterPort.toString)).toEnd(10.minutes)
        withClue(aloneOut.mkString("\n")) {
          aloneExit.isDefined shouldBe true
          aloneExit should not be Some(0)
          aloneOut should contain(s"hello-robot failed: no gateway at 127.0.0.1:$clusterPort (ROBOTS_GATEWAY_HOST, " +
            "ROBOTS_GATEWAY_PORT); start the demo first (`./sbt run` in the naogateway clone), then this app again")
        }
      } finally TempFiles.deleteRecursively(work)
    }
  }
}

/** `./sbt firstApp`: runs [[FirstAppSpec]] alone and exits 1 when it fails (it is not part of `./sbt test`). */
object FirstAppCheck {
  def main(args: Array[String]): Unit =
    if (!org.scalatest.tools.Runner.run(Array("-oD", "-s", classOf[FirstAppSpec].getName))) sys.exit(1)
}
