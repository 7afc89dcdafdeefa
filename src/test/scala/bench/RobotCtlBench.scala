package bench

import java.io.File
import java.net.InetSocketAddress
import java.util.concurrent.TimeUnit

import scala.collection.immutable.ListMap
import scala.concurrent.Await
import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

import akka.actor.typed.scaladsl.AskPattern._
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, ActorSystem, Scheduler}
import akka.util.Timeout
import com.typesafe.config.ConfigFactory

import naogateway.launcher.RobotCtl
import apps.control.{ControlServer, ControlSettings, FleetStub}
import naogateway.testkit.TestLoopback
import naogateway.sim.{Fleet, FleetSettings}
import naogateway.access.GatewayAccess
import naogateway.gateway.{Gateway, GatewaySettings}
import robotmiddleware.{MiddlewareSettings, RobotMiddleware}
import naogateway.api.GatewayAddresses

/** `robotctl status` as an operator runs it: a fresh JVM (`java -cp <this classpath> naogateway.launcher.RobotCtl
  * status`) against a gateway, middleware and control port in this JVM, over loopback. Wall time from process start to
  * exit, median of [[Runs]] runs after one warm-up run:
  *
  *   - `robotctl_status_wall_ms`: three simulated robots (the demo's fleet), default JVM options.
  *   - `robotctl_status_wall_ms_c1`: the same with `-XX:TieredStopAtLevel=1 -XX:+UseSerialGC`, options that suit a
  *     short-lived client JVM.
  *   - `robotctl_status_1000_wall_ms`: a control port in front of 1,000 stand-in robots (the answer is 1,002 lines).
  *   - `robotctl_jvm_floor_ms`: robotctl with no gateway to reach (it fails at once): the JVM start and class loading.
  */
object RobotCtlBench extends Benchmark {
  val name = "robotctl"

  private val Runs = 7

  def run(): ListMap[String, Double] = {
    val config = ConfigFactory.load(ConfigFactory.parseString(
        """naogateway.link.bind-address = "127.0.0.1"
        |naogateway.link.robot-port = 0
        |naogateway.game-controller.enabled = off
        |akka.loglevel = "WARNING"
        |""".stripMargin))
    val system = ActorSystem[Nothing](Behaviors.empty, "robotctl-bench", config)
    implicit val scheduler: Scheduler = system.scheduler
    implicit val timeout: Timeout = Timeout(30.seconds)
    try {
      val settings = ControlSettings(system).copy(host = "127.0.0.1", port = 0)
      def addressOf(control: ActorRef[ControlServer.Command]): String =
        s"127.0.0.1:${Await.result(control.ask[InetSocketAddress](ControlServer.GetAddress(_)), 30.seconds).getPort}"

      val gateway = system.systemActorOf(Gateway(GatewaySettings(system)), "gateway")
      val middleware = system.systemActorOf(RobotMiddleware(gateway, MiddlewareSettings(system)), "middleware")
      val demo = addressOf(system.systemActorOf(ControlServer(middleware, settings), "control"))
      val thousand =
        addressOf(system.systemActorOf(ControlServer.withInterface(new FleetStub(1000), settings), "control-1000"))
      val robots = Await.result(gateway.ask[GatewayAddresses](GatewayAccess.GetAddresses(_)), 30.seconds).robots
      Await.result(
        Fleet.start(system,
          FleetSettings(new InetSocketAddress("127.0.0.1", robots.getPort), Vector(1, 2, 3),
            faithfulLink = false, firstAddress = TestLoopback.block(3))),
        60.seconds
      )
      awaitOnline(demo, 3)

      val floorPort = {
        val s = new java.net.ServerSocket(0);
        try s.getLocalPort
        finally s.close()
      }
      val c1 = Seq("-XX:TieredStopAtLevel=1", "-XX:+UseSerialGC")
      ListMap(
        "robotctl_status_wall_ms" -> wallMillis(Nil, Seq("--control", demo, "status"), expectExit = 0),
        "robotctl_status_wall_ms_c1" -> wallMillis(c1, Seq("--control", demo, "status"), expectExit = 0),
        "robotctl_status_1000_wall_ms" -> wallMillis(Nil, Seq("--control", thousand, "status"), expectExit = 0),
        "robotctl_jvm_floor_ms" -> wallMillis(Nil, Seq("--control", s"127.0.0.1:$floorPort", "status"), expectExit = 1)
      )
    } finally {
      system.terminate()
      Await.result(system.whenTerminated, 60.seconds)
    }
  }

  /** Waits (at most a minute) until robotctl, run in this JVM, sees `robots` robots online. */
  private def awaitOnline(control: String, robots: Int): Unit = {
    val deadline = 60.seconds.fromNow
    def online(): Int = {
      val lines = Vector.newBuilder[String]
      RobotCtl.run(Seq("--control", control, "status"), _ => None, lines += _, _ => ())
      lines.result().count(_.contains(" online "))
    }
    while (online() < robots) {
      if (deadline.isOverdue()) throw new IllegalStateException(s"$robots robots did not come online within a minute")
      Thread.sleep(200)
    }
  }

  /** The median wall time of `java <jvmOptions> -cp <classpath> naogateway.launcher.RobotCtl <args>`, in ms, after a
    * warm-up run.
    */
  private def wallMillis(jvmOptions: Seq[String], args: Seq[String], expectExit: Int): Double = {
    val java = s"${System.getProperty("java.home")}/bin/java"
    val command =
      (java +: jvmOptions) ++ Seq("-cp", System.getProperty("java.class.path"), "naogateway.launcher.RobotCtl") ++ args
    def once(): Double = {
      val start = System.nanoTime()
      val process = new ProcessBuilder(command.asJava)
        .redirectOutput(ProcessBuilder.Redirect.to(new File("/dev/null")))
        .redirectError(ProcessBuilder.Redirect.to(new File("/dev/null")))
        .start()
      if (!process.waitFor(60, TimeUnit.SECONDS)) {
        process.destroyForcibly()
        throw new IllegalStateException(s"robotctl ${args.mkString(" ")} did not end within 60 s")
      }
      val millis = (System.nanoTime() - start) / 1e6
      if (process.exitValue() != expectExit)
        throw new IllegalStateException(s"robotctl ${args.mkString(" ")} exited ${process.exitValue()}")
      millis
    }
    once()
    val times = Vector.fill(Runs)(once()).sorted
    println(
      f"  robotctl ${(jvmOptions ++ args).mkString(" ")}: median ${times(Runs / 2)}%.0f ms, min ${times.head}%.0f, max ${times.last}%.0f")
    times(Runs / 2)
  }
}
