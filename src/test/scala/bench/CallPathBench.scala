package bench

import java.io.File
import java.net.InetSocketAddress
import java.nio.charset.StandardCharsets
import java.nio.file.Files

import scala.collection.immutable.ListMap
import scala.concurrent.Await
import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.util.{Failure, Success, Try}

import akka.actor.typed.scaladsl.AskPattern._
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, ActorSystem, Scheduler}
import akka.cluster.typed.{Cluster, Join}
import akka.util.Timeout
import com.typesafe.config.{Config, ConfigFactory}

import apps.datagram.{DatagramDoor, DatagramDoorSettings}
import apps.zeromq.{PythonEnv, ZeroMqEndpoint, ZeroMqSettings}
import naogateway.wire.RpcCall
import naogateway.access.{GatewayAccess, RobotAccess}
import naogateway.api.{CallResult, GatewayAddresses, LinkStats, RobotEvent, RobotSnapshot, VisionFrame}
import naogateway.gateway.{Gateway, GatewaySettings}
import robotmiddleware.cluster.MiddlewareCluster
import robotmiddleware.{MiddlewareSettings, RobotClient, RobotInterface, RobotMiddleware}

/** The call path users feel: an app's `system.ping` to a robot and back through each door, all to one plain-socket
  * robot (a thread on a DatagramChannel answering the RPC frame at once, keep-alives from another: no simulator),
  * beside the raw UDP floor and the command round trip of a peer, MAVSDK, measured in the same run. Paced at one call
  * per millisecond after a warm-up, as `GatewayBench`'s round trips; nearest-rank percentiles in microseconds.
  *
  *   - `callpath_raw_udp_*`: the floor, a plain request/answer between two DatagramChannels (`GatewayBench`'s).
  *   - `callpath_gateway_*`: the gateway alone, the call asked of the robot's command owner (`ResponseActor`).
  *   - `callpath_gateway_signed_*`: the same with signing on (protocol.md 6.7): the gateway signs each request with the
  *     robot's key, the robot checks it and signs its reply, the gateway checks that; ratio
  *     `callpath_gateway_signed_over_gateway_p50`.
  *   - `callpath_interface_*`: a Scala app through `RobotInterface` in the gateway's JVM and actor system.
  *   - `callpath_cluster_*`: a Scala app on another cluster node (its own actor system in this JVM, Artery over
  *     loopback TCP), through `RobotInterface`.
  *   - `callpath_python_*`: the Python client (apps/python) over the ZeroMQ endpoint, a process of its own.
  *   - `callpath_python_door_*`: the same client and endpoint in front of a `RobotInterface` that answers every call at
  *     once: the ZeroMQ door's own part (sockets, the endpoint, the client), without middleware or robot.
  *   - `callpath_python_datagram_*`: the same client's `DatagramGatewayClient` through the datagram door
  *     (`apps.datagram.DatagramDoor`): the same requests, one UDP datagram each way, no I/O thread on either side.
  *   - `callpath_python_datagram_door_*`: that client and door in front of the interface that answers at once.
  *   - `callpath_mavsdk_*`: MAVSDK (the `mavsdk` package) arming a pymavlink-played vehicle on loopback, each arm one
  *     COMMAND_LONG answered by a COMMAND_ACK (src/test/python/bench/mavsdk_peer.py); absent (null) when it cannot be
  *     installed or run here, the reason in the progress lines.
  *   - `callpath_mavsdk_grpc_*`: the same with MAVSDK's gRPC ground side (`mavsdk-grpc`, which the `mavsdk` package was
  *     up to version 3: Python asks the bundled mavsdk_server over gRPC), in a venv of its own.
  *   - `callpath_zeromq_floor_*`: the ZeroMQ transport alone, a pyzmq DEALER to a pyzmq ROUTER echo in a second Python
  *     process (src/test/python/bench/zeromq_floor.py): the floor of any door over ZeroMQ.
  *     `callpath_python_udp_floor_*`: a plain UDP echo between the same two Python processes, the floor of any Python
  *     process-to-process exchange.
  *   - ratios: `callpath_gateway_over_raw_udp_p50`, `callpath_interface_over_gateway_p50`,
  *     `callpath_cluster_over_gateway_p50`, `callpath_python_over_mavsdk_p50`, `callpath_python_over_mavsdk_grpc_p50`,
  *     `callpath_python_datagram_over_mavsdk_p50`.
  *
  * The gateway's actor system is a cluster node (the gateway role) for the whole group, so every door meets the same
  * gateway. The Python door and the peer need python3 and pip; both run in one venv under apps/target.
  */
object CallPathBench extends Benchmark {
  val name = "callpath"

  /** The parts to run: `quick` takes only the raw floor, the gateway alone and `RobotInterface` (once, with the
    * wake-ups per call); everything when empty.
    */
  var parts: Set[String] = Set.empty
  override def quietSensitive: Boolean = parts.isEmpty

  /** Calls through the gateway before anything is measured: the JIT's, for the path every door shares (the actors, the
    * codecs, the port). With only the usual warm-up the gateway alone, measured first, came out 1.5-1.8 x slower than
    * the same calls measured again a minute later in the same run.
    */
  private val JitWarmup = 10000
  private val PythonWarmup = 1000
  private val PythonSamples = 2000
  private val PeerWarmup = 200
  private val PeerSamples = 1000
  private val startedAt = System.nanoTime()

  private def progress(line: String): Unit = println(f"[callpath ${(System.nanoTime() - startedAt) / 1e9}%6.1fs] $line")

  /** The Python packages of the client's specs, plus the peer's (pinned). */
  private val PeerRequirements = Seq("mavsdk==4.1.0", "pymavlink==2.4.50")

  /** The gRPC peer's own venv: mavsdk-grpc's generated code needs a grpcio newer than the one the client's protoc
    * (grpcio-tools) pins, so the two cannot share one. Pinned as pip resolved them.
    */
  private val GrpcPeerRequirements = Seq("mavsdk-grpc==4.0.5", "pymavlink==2.4.50", "grpcio==1.85.3",
    "protobuf==7.36.2", "fastcrc==0.5.0", "lxml==6.1.3", "typing_extensions==4.16.0")

  def run(): ListMap[String, Double] =
    if (parts("quick")) quick() else if (parts("demo")) demoSpin() else full()

  /** The demo (the launcher's main on this classpath, as `IdleCpuBench` falls back to) with the answer spin off, then
    * on: its port loop's threads' CPU and wake-ups a second over [[DemoWindow]] after [[DemoSettle]], and the process's
    * CPU. The ball follower steers robot 1 the whole time, so requests leave and the spin runs: what it costs a demo.
    */
  private def demoSpin(): ListMap[String, Double] = {
    val figures = Seq("off" -> "0us", "on" -> "50us").flatMap { case (label, spin) =>
      val (process, loop, wakes) = demoLoop(spin)
      progress(f"demo, spin $label: process $process%.1f %%, port loop $loop%.2f %% of a core, " +
        f"port loop wake-ups $wakes%.0f a second")
      Seq(
        s"callpath_demo_spin_${label}_cpu_pct" -> process,
        s"callpath_demo_spin_${label}_loop_cpu_pct" -> loop,
        s"callpath_demo_spin_${label}_loop_wakeups_s" -> wakes
      )
    }
    ListMap(figures: _*)
  }

  private val DemoSettle = 30.seconds
  private val DemoWindow = 30.seconds

  private def demoLoop(spin: String): (Double, Double, Double) = {
    import scala.jdk.CollectionConverters._
    import Packaged.ownPorts
    val log = java.nio.file.Paths.get("target", "bench", s"demo-spin-$spin.log").toAbsolutePath
    Files.createDirectories(log.getParent)
    Files.deleteIfExists(log)
    val logging =
      Option(getClass.getClassLoader.getResource("logback.xml")).map(u => s"-Dlogback.configurationFile=$u")
    val command = Seq(s"${System.getProperty("java.home")}/bin/java") ++ logging ++
      Seq(s"-Dnaogateway.dispatcher.port-loop.answer-spin=$spin", "-cp", System.getProperty("java.class.path"),
        "naogateway.launcher.Launcher")
    val output = log.resolveSibling(s"demo-spin-$spin.out").toFile
    val builder = new ProcessBuilder(command.asJava).redirectErrorStream(true)
      .redirectOutput(ProcessBuilder.Redirect.to(output))
    ownPorts(builder.environment(), log)
    val process = builder.start()
    try {
      def online = Try(Files.readAllLines(log).asScala.count(_.contains("online at"))).getOrElse(0)
      val deadline = 120.seconds.fromNow
      while (online < 3 && process.isAlive && deadline.hasTimeLeft()) Thread.sleep(500)
      if (!process.isAlive) progress(s"the demo ended with ${process.exitValue()} (see $output)")
      Thread.sleep(DemoSettle.toMillis)
      val pid = process.pid()
      // "<system>-naogateway.dispatcher-<n>" cut to 15 characters (the ZeroMQ link's dispatcher's too: both printed).
      def loopThreads(m: Map[Long, ThreadWakeups.Counts]) = m.filter(_._2.name.contains("-naog"))
      val (c0, b0, t0) = (Packaged.cpuNanos(pid), ThreadWakeups.snapshot(pid.toString), System.nanoTime())
      Thread.sleep(DemoWindow.toMillis)
      val (c1, b1, t1) = (Packaged.cpuNanos(pid), ThreadWakeups.snapshot(pid.toString), System.nanoTime())
      val seconds = (t1 - t0) / 1e9
      val processPct = (for (a <- c0; b <- c1) yield (b - a) / 1e7 / seconds).getOrElse(Double.NaN)
      val before = loopThreads(b0)
      val after = loopThreads(b1)
      progress(s"demo, answer-spin $spin: " + after.toVector.sortBy(_._1).map { case (tid, a) =>
        val b = before.get(tid)
        f"${a.name}#$tid ${(a.cpuTicks - b.fold(0L)(_.cpuTicks)) / seconds}%.2f %% CPU, " +
          f"${(a.voluntary - b.fold(0L)(_.voluntary)) / seconds}%.0f wake-ups/s"
      }.mkString("; "))
      // Clock ticks are hundredths of a second on Linux.
      val loopPct = after.map { case (tid, a) => a.cpuTicks - before.get(tid).fold(0L)(_.cpuTicks) }.sum / seconds
      val wakes = after.map { case (tid, a) => a.voluntary - before.get(tid).fold(0L)(_.voluntary) }.sum / seconds
      (processPct, loopPct, wakes)
    } finally {
      process.destroy()
      if (!process.waitFor(20, java.util.concurrent.TimeUnit.SECONDS)) process.destroyForcibly()
    }
  }

  /** `op`'s samples, with the wake-ups of this JVM's threads per call while it ran (`calls` calls in all), and the CPU
    * time per call of the threads named `cpuOf` (the port loop's).
    */
  private def woken(what: String, calls: Int, cpuOf: String = "naogateway.dispatcher")(
      op: => Array[Long]): Array[Long] = {
    val threads = java.lang.management.ManagementFactory.getThreadMXBean
    def cpu(named: String) = Thread.getAllStackTraces.keySet.asScala.toVector.filter(_.getName.contains(named))
      .map(t => t.getId -> threads.getThreadCpuTime(t.getId)).toMap
    val before = ThreadWakeups.snapshot()
    val cpuBefore = cpu(cpuOf)
    val robotBefore = cpu("plain-robot-answers")
    val samples = op
    val cpuAfter = cpu(cpuOf)
    val robotAfter = cpu("plain-robot-answers")
    val (all, busiest) = ThreadWakeups.perCall(before, ThreadWakeups.snapshot(), calls)
    def perCall(after: Map[Long, Long], before: Map[Long, Long]) =
      after.map { case (id, t) => t - before.getOrElse(id, 0L) }.sum.toDouble / calls / 1e3
    progress(f"$what: $all%.2f wake-ups per call in this JVM; " +
      busiest.map { case (t, n) => f"$t $n%.2f" }.mkString(", ") +
      f"; CPU per call: port loop ${perCall(cpuAfter, cpuBefore)}%.1f us, the robot's answering thread " +
      f"${perCall(robotAfter, robotBefore)}%.1f us")
    samples
  }

  /** The raw floor, then the gateway alone and `RobotInterface` with the port loop's answer spin off and on (a gateway
    * node each), each with its wake-ups per call: the spin's gain as ratios of one run.
    */
  private def quick(): ListMap[String, Double] = GatewayBench.quietLogging {
    progress(s"${Runtime.getRuntime.availableProcessors} cores, load average ${GatewayBench.loadAverage()}")
    val total = GatewayBench.RttWarmup + GatewayBench.RttSamples
    val raw = woken("raw udp", total)(GatewayBench.rawRoundTrips())
    report("raw udp", raw)
    def p50(s: Array[Long]) = GatewayBench.percentile(s, 0.50) / 1e3
    def p99(s: Array[Long]) = GatewayBench.percentile(s, 0.99) / 1e3
    val figures = Seq("off" -> Some("0us"), "on" -> None).flatMap { case (label, spin) =>
      val gateway = new GatewayNode(answerSpin = spin)
      try {
        val robot = new PlainRobot(gateway.addresses.robots, 15.minutes)
        try {
          gateway.awaitOnline(1)
          gateway.pings(JitWarmup)
          val alone = woken(s"gateway alone, spin $label", total)(gateway.pings())
          report(s"gateway alone, spin $label", alone)
          val local = Await.result(RobotClient.connect(gateway.system, gateway.middleware, "bench-local"), 30.seconds)
          appCalls(local, JitWarmup - GatewayBench.RttWarmup)
          val interface = woken(s"RobotInterface, spin $label", total)(appCalls(local))
          report(s"RobotInterface, spin $label", interface)
          local.close()
          gateway.spinCounts().foreach { case (n, hits) =>
            progress(f"answer spins: $n, ended by an arrival: $hits (${hits * 100.0 / math.max(1L, n)}%.0f %%)")
          }
          val suffix = if (spin.isEmpty) "" else s"_spin_$label"
          Seq(
            s"callpath_gateway${suffix}_p50_us" -> p50(alone),
            s"callpath_gateway${suffix}_p99_us" -> p99(alone),
            s"callpath_interface${suffix}_p50_us" -> p50(interface),
            s"callpath_interface${suffix}_p99_us" -> p99(interface),
            s"callpath_gateway${suffix}_over_raw_udp_p50" -> p50(alone) / p50(raw),
            s"callpath_interface${suffix}_over_gateway_p50" -> p50(interface) / p50(alone)
          )
        } finally robot.close()
      } finally gateway.stop()
    }
    progress(s"done, load average ${GatewayBench.loadAverage()}")
    ListMap("callpath_raw_udp_p50_us" -> p50(raw), "callpath_raw_udp_p99_us" -> p99(raw)) ++ figures
  }

  private def full(): ListMap[String, Double] = GatewayBench.quietLogging {
    progress(s"${Runtime.getRuntime.availableProcessors} cores, load average ${GatewayBench.loadAverage()}")
    val raw = GatewayBench.rawRoundTrips()
    report("raw udp", raw)
    val gateway = new GatewayNode
    try {
      val robot = new PlainRobot(gateway.addresses.robots, 15.minutes)
      try {
        gateway.awaitOnline(1)
        progress(s"warming up: $JitWarmup calls through the gateway")
        gateway.pings(JitWarmup)
        val alone = gateway.pings()
        report("gateway alone", alone)
        val local = Await.result(RobotClient.connect(gateway.system, gateway.middleware, "bench-local"), 30.seconds)
        progress(s"warming up: $JitWarmup calls through RobotInterface")
        val interface = appCalls(local, JitWarmup)
        report("RobotInterface, same JVM", interface)
        local.close()
        val cluster = otherNode(gateway.clusterPort)(appCalls)
        report("RobotInterface, other cluster node", cluster)
        val python = pythonCalls(gateway.zeroMq())
        python.fold(why => progress(s"python client not measured: $why"),
          p => progress(f"python client: p50 ${p._1}%.0f us, p99 ${p._2}%.0f us"))
        val door = pythonCalls(gateway.zeroMqAnswering())
        door.fold(
          why => progress(s"python door alone not measured: $why"),
          p => progress(f"python client to an endpoint that answers at once: p50 ${p._1}%.0f us, p99 ${p._2}%.0f us")
        )
        val datagram = datagramCalls(gateway.datagram())
        datagram.fold(
          why => progress(s"python client over the datagram door not measured: $why"),
          p => progress(f"python client over the datagram door: p50 ${p._1}%.0f us, p99 ${p._2}%.0f us")
        )
        val datagramDoor = datagramCalls(gateway.datagramAnswering())
        datagramDoor.fold(
          why => progress(s"datagram door alone not measured: $why"),
          p =>
            progress(f"python client to a datagram door that answers at once: p50 ${p._1}%.0f us, " +
              f"p99 ${p._2}%.0f us")
        )
        val zeroMqFloor = floor("zeromq")
        zeroMqFloor.fold(why => progress(s"ZeroMQ floor not measured: $why"),
          p => progress(f"ZeroMQ floor (pyzmq to a pyzmq echo): p50 ${p._1}%.0f us, p99 ${p._2}%.0f us"))
        val udpFloor = floor("udp")
        udpFloor.fold(
          why => progress(s"Python UDP floor not measured: $why"),
          p =>
            progress(f"Python UDP floor (a UDP echo between two Python processes): p50 ${p._1}%.0f us, " +
              f"p99 ${p._2}%.0f us")
        )
        val signed = signedGatewayCalls()
        report("gateway alone, signed", signed)
        val peer = mavsdk()
        peer.fold(why => progress(s"MAVSDK not measured: $why"),
          p => progress(f"MAVSDK command: p50 ${p._1}%.0f us, p99 ${p._2}%.0f us"))
        val grpcPeer = mavsdkGrpc()
        grpcPeer.fold(
          why => progress(s"MAVSDK over gRPC not measured: $why"),
          p => progress(f"MAVSDK command over gRPC (mavsdk_server): p50 ${p._1}%.0f us, p99 ${p._2}%.0f us")
        )
        progress(s"done, load average ${GatewayBench.loadAverage()}")
        def p50(s: Array[Long]) = GatewayBench.percentile(s, 0.50) / 1e3
        def p99(s: Array[Long]) = GatewayBench.percentile(s, 0.99) / 1e3
        val nan = Double.NaN
        ListMap(
          "callpath_raw_udp_p50_us" -> p50(raw),
          "callpath_raw_udp_p99_us" -> p99(raw),
          "callpath_gateway_p50_us" -> p50(alone),
          "callpath_gateway_p99_us" -> p99(alone),
          "callpath_gateway_signed_p50_us" -> p50(signed),
          "callpath_gateway_signed_p99_us" -> p99(signed),
          "callpath_interface_p50_us" -> p50(interface),
          "callpath_interface_p99_us" -> p99(interface),
          "callpath_cluster_p50_us" -> p50(cluster),
          "callpath_cluster_p99_us" -> p99(cluster),
          "callpath_python_p50_us" -> python.fold(_ => nan, _._1),
          "callpath_python_p99_us" -> python.fold(_ => nan, _._2),
          "callpath_python_door_p50_us" -> door.fold(_ => nan, _._1),
          "callpath_python_door_p99_us" -> door.fold(_ => nan, _._2),
          "callpath_python_datagram_p50_us" -> datagram.fold(_ => nan, _._1),
          "callpath_python_datagram_p99_us" -> datagram.fold(_ => nan, _._2),
          "callpath_python_datagram_door_p50_us" -> datagramDoor.fold(_ => nan, _._1),
          "callpath_python_datagram_door_p99_us" -> datagramDoor.fold(_ => nan, _._2),
          "callpath_zeromq_floor_p50_us" -> zeroMqFloor.fold(_ => nan, _._1),
          "callpath_zeromq_floor_p99_us" -> zeroMqFloor.fold(_ => nan, _._2),
          "callpath_python_udp_floor_p50_us" -> udpFloor.fold(_ => nan, _._1),
          "callpath_python_udp_floor_p99_us" -> udpFloor.fold(_ => nan, _._2),
          "callpath_mavsdk_p50_us" -> peer.fold(_ => nan, _._1),
          "callpath_mavsdk_p99_us" -> peer.fold(_ => nan, _._2),
          "callpath_mavsdk_grpc_p50_us" -> grpcPeer.fold(_ => nan, _._1),
          "callpath_mavsdk_grpc_p99_us" -> grpcPeer.fold(_ => nan, _._2),
          "callpath_gateway_over_raw_udp_p50" -> p50(alone) / p50(raw),
          "callpath_gateway_signed_over_gateway_p50" -> p50(signed) / p50(alone),
          "callpath_interface_over_gateway_p50" -> p50(interface) / p50(alone),
          "callpath_cluster_over_gateway_p50" -> p50(cluster) / p50(alone),
          "callpath_python_over_mavsdk_p50" ->
            (for { py <- python.toOption; mav <- peer.toOption } yield py._1 / mav._1).getOrElse(nan),
          "callpath_python_datagram_over_mavsdk_p50" ->
            (for { py <- datagram.toOption; mav <- peer.toOption } yield py._1 / mav._1).getOrElse(nan),
          "callpath_zeromq_floor_over_mavsdk_p50" ->
            (for { z <- zeroMqFloor.toOption; mav <- peer.toOption } yield z._1 / mav._1).getOrElse(nan),
          "callpath_python_over_mavsdk_grpc_p50" ->
            (for { py <- python.toOption; mav <- grpcPeer.toOption } yield py._1 / mav._1).getOrElse(nan)
        )
      } finally robot.close()
    } finally gateway.stop()
  }

  private def report(what: String, samples: Array[Long]): Unit =
    progress(f"$what: p50 ${GatewayBench.percentile(samples, 0.50) / 1e3}%.0f us, " +
      f"p99 ${GatewayBench.percentile(samples, 0.99) / 1e3}%.0f us, " +
      f"max ${samples.max / 1e3}%.0f us over ${samples.length}")

  /** `system.ping` through an app's `RobotInterface`, paced. */
  private def appCalls(app: RobotInterface): Array[Long] = appCalls(app, GatewayBench.RttWarmup)

  /** The same after `warmup` calls: the interface's own code (middleware, guard, futures) gets the JIT's warm-up the
    * gateway alone gets ([[JitWarmup]]), so their ratio compares two steady states.
    */
  private def appCalls(app: RobotInterface, warmup: Int): Array[Long] = {
    def once(): Long = {
      val start = System.nanoTime()
      Await.result(app.call(1, "system", "ping"), 10.seconds)
      System.nanoTime() - start
    }
    GatewayBench.paced(warmup)(() => once())
    GatewayBench.paced(GatewayBench.RttSamples)(() => once())
  }

  /** An app node of the gateway's cluster, in its own actor system; `body` gets the app's interface. */
  private def otherNode[T](gatewayPort: Int)(body: RobotInterface => T): T = {
    val overrides = ConfigFactory.parseString(
      s"""robotmiddleware.cluster.gateway-port = $gatewayPort
         |akka.cluster.jmx.multi-mbeans-in-same-jvm = on
         |akka.loglevel = "WARNING"
         |""".stripMargin)
    val node = MiddlewareCluster.start[Nothing](Behaviors.empty, MiddlewareCluster.AppRole, overrides)
    try {
      Await.result(MiddlewareCluster.up(node), 60.seconds)
      implicit val ec: scala.concurrent.ExecutionContext = node.executionContext
      val connecting = RobotClient.find(node, 30.seconds).flatMap(RobotClient.connect(node, _, "bench-remote"))
      val app = Await.result(connecting, 60.seconds)
      try body(app)
      finally app.close()
    } finally {
      node.terminate()
      Await.result(node.whenTerminated, 60.seconds)
    }
  }

  /** The venv of the Python door and the peer: the client's requirements plus the peer's, or why there is none. */
  private def venv(): Either[String, File] = {
    val client = new String(Files.readAllBytes(PythonEnv.requirements.toPath), StandardCharsets.UTF_8)
    venvOf("python-bench-venv", client + "\n# bench.CallPathBench's peer\n" + PeerRequirements.mkString("\n") + "\n")
  }

  /** A venv under apps/target made from `requirements` (reused while they stay the same), or why there is none. */
  private def venvOf(name: String, requirements: String): Either[String, File] = {
    val wanted = new File(PythonEnv.root, s"target/bench/$name-requirements.txt")
    wanted.getParentFile.mkdirs()
    Files.write(wanted.toPath, requirements.getBytes(StandardCharsets.UTF_8))
    Try(PythonEnv.environment(new File(PythonEnv.root, s"apps/target/$name"), wanted)).fold(e => Left(s"$e"), identity)
  }

  /** Runs a script of src/test/python/bench; its one JSON line as (p50, p99) in microseconds, or why not. */
  private def script(python: File, name: String, args: Seq[String]): Either[String, (Double, Double)] = {
    val log = new File(PythonEnv.root, s"target/bench/$name.log")
    val env = Map(
      "NAOGATEWAY_PY_GEN" -> new File(PythonEnv.root, "apps/target/python-gen").getPath,
      "PYTHONPATH" -> new File(PythonEnv.root, "apps/python").getPath,
      "PYTHONDONTWRITEBYTECODE" -> "1"
    )
    // stderr goes to the log too: only the last JSON line is read.
    val path = new File(PythonEnv.root, s"src/test/python/bench/$name").getPath
    Try(PythonEnv.run(Seq(python.getPath, "-u", path) ++ args,
        10.minutes, log, env)) match {
      case Failure(e) => Left(s"$name did not finish: $e")
      case Success((code, output)) =>
        val Figure = """.*"p50_us": ([0-9.]+), "p99_us": ([0-9.]+).*""".r
        val Error = """.*"error": "(.*)".*""".r
        output.linesIterator.toVector.reverse.collectFirst {
          case Figure(p50, p99) => Right(p50.toDouble -> p99.toDouble)
          case Error(why)       => Left(why)
        }.getOrElse(Left(s"$name exited with $code and no figures (see ${log.getPath})"))
    }
  }

  private def pythonCalls(endpoint: ZeroMqEndpoint.Addresses): Either[String, (Double, Double)] =
    venv().flatMap(python =>
      script(
        python,
        "zeromq_calls.py",
        Seq("--endpoint", endpoint.requests,
          "--publish", endpoint.publish,
          "--robot", "1", "--warmup", PythonWarmup.toString, "--samples", PythonSamples.toString)
      ))

  private def datagramCalls(door: InetSocketAddress): Either[String, (Double, Double)] =
    venv().flatMap(python =>
      script(
        python,
        "zeromq_calls.py",
        Seq("--datagram", s"${door.getAddress.getHostAddress}:${door.getPort}",
          "--robot", "1", "--warmup", PythonWarmup.toString, "--samples", PythonSamples.toString)
      ))

  /** A floor of the Python door (`zeromq` or `udp`): two Python processes and the transport, nothing else. */
  private def floor(transport: String): Either[String, (Double, Double)] =
    venv().flatMap(python =>
      script(python, "zeromq_floor.py",
        Seq("--transport", transport, "--warmup", PythonWarmup.toString, "--samples", PythonSamples.toString)))

  private def mavsdkGrpc(): Either[String, (Double, Double)] =
    venvOf("python-peer-grpc-venv", GrpcPeerRequirements.mkString("", "\n", "\n"))
      .flatMap(python =>
        script(python, "mavsdk_peer.py",
          Seq("--grpc", "--warmup", PeerWarmup.toString, "--samples", PeerSamples.toString)))

  private def mavsdk(): Either[String, (Double, Double)] =
    venv().flatMap(python =>
      script(python, "mavsdk_peer.py", Seq("--warmup", PeerWarmup.toString, "--samples", PeerSamples.toString)))

  /** The gateway, its middleware and (on request) its ZeroMQ endpoint, in one actor system that is a cluster node. */
  /** The team key of the signed variant (protocol.md 9.14's test key). */
  private val TeamKeyHex = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f"

  /** A gateway node; `signing`: with the team key, so robot 1 must sign and everything to it is signed. */
  private final class GatewayNode(signing: Boolean = false, answerSpin: Option[String] = None) {
    private val overrides: Config = ConfigFactory.parseString(
      (if (signing) s"""naogateway.signing.key = "$TeamKeyHex"\n""" else "") +
        answerSpin.fold("")(s => s"naogateway.dispatcher.port-loop.answer-spin = $s\n") +
        """naogateway.link.bind-address = "127.0.0.1"
        |naogateway.link.robot-port = 0
        |naogateway.game-controller.enabled = off
        |robotmiddleware.cluster.gateway-port = 0
        |akka.cluster.seed-nodes = []
        |akka.cluster.jmx.multi-mbeans-in-same-jvm = on
        |akka.loglevel = "WARNING"
        |# As the launcher runs them: the middleware and the datagram door on the gateway's robot dispatcher.
        |robotmiddleware.dispatcher = "naogateway.dispatcher"
        |apps.datagram-door.dispatcher = "naogateway.dispatcher"
        |# A socket-loop thread for each of the bench's two endpoints.
        |apps.zeromq.dispatcher.thread-pool-executor.fixed-pool-size = 2
        |""".stripMargin)
    private val config = MiddlewareCluster.config(MiddlewareCluster.GatewayRole, overrides)
    val system: ActorSystem[GatewayAccess.Command] =
      MiddlewareCluster.start(Gateway(GatewaySettings.fromConfig(config.getConfig("naogateway"))), config)
    private val cluster = Cluster(system)
    cluster.manager ! Join(cluster.selfMember.address)
    val clusterPort: Int = cluster.selfMember.address.port.get
    private implicit val scheduler: Scheduler = system.scheduler
    private implicit val timeout: Timeout = Timeout(30.seconds)
    val addresses: GatewayAddresses = Await.result(system.ask(GatewayAccess.GetAddresses(_)), 30.seconds)
    val middleware: ActorRef[RobotMiddleware.Command] =
      system.systemActorOf(RobotMiddleware(system, MiddlewareSettings(system)), "middleware",
        RobotMiddleware.dispatcher(MiddlewareSettings(system)))

    def robot(robotId: Int): Option[ActorRef[RobotAccess.Command]] =
      Await.result(system.ask[Option[ActorRef[RobotAccess.Command]]](GatewayAccess.GetRobotAccess(robotId, _)),
        30.seconds)

    def awaitOnline(robotId: Int): Unit = {
      val deadline = 30.seconds.fromNow
      def online =
        robot(robotId).exists(r => Await.result(r.ask[RobotSnapshot](RobotAccess.GetSnapshot(_)), 30.seconds).online)
      while (!online) {
        if (deadline.isOverdue()) throw new IllegalStateException(s"robot $robotId did not come online")
        Thread.sleep(50)
      }
    }

    /** The port loop's answer spins and hits so far ([[naogateway.transport.PortLoop.spinCounts]]), asked on its
      * thread.
      */
    def spinCounts(): Option[(Long, Long)] = {
      val loop = system.dispatchers.lookup(akka.actor.typed.DispatcherSelector.fromConfig("naogateway.dispatcher"))
      val answer = scala.concurrent.Promise[Option[(Long, Long)]]()
      loop.execute(() => answer.success(naogateway.transport.PortLoop.current.map(_.spinCounts)))
      Await.result(answer.future, 10.seconds)
    }

    /** The gateway alone: `system.ping` asked of the robot's command owner. */
    def pings(warmup: Int = GatewayBench.RttWarmup): Array[Long] = {
      val robotRef = robot(1).getOrElse(throw new IllegalStateException("the gateway does not know robot 1"))
      val connected = Await.result(robotRef.ask[RobotAccess.Opened](RobotAccess.Open(_)), 30.seconds)
      val ping = RpcCall("system", "ping", Vector.empty)
      def once(): Long = {
        val start = System.nanoTime()
        val answer = Await.result(connected.response.ask[CallResult](RobotAccess.Call(ping, _)), 10.seconds)
        val took = System.nanoTime() - start
        require(answer.result.isRight, s"system.ping failed: $answer")
        took
      }
      GatewayBench.paced(warmup)(() => once())
      GatewayBench.paced(GatewayBench.RttSamples)(() => once())
    }

    private val zeroMqSettings = ZeroMqSettings(system).copy(bind = "tcp://127.0.0.1:*", publish = "tcp://127.0.0.1:*")

    private def addresses(endpoint: ActorRef[ZeroMqEndpoint.Command]): ZeroMqEndpoint.Addresses =
      Await.result(endpoint.ask[ZeroMqEndpoint.Addresses](ZeroMqEndpoint.GetAddresses(_)), 30.seconds)

    /** Starts the ZeroMQ endpoint on free loopback ports; its addresses. */
    def zeroMq(): ZeroMqEndpoint.Addresses =
      addresses(system.systemActorOf(ZeroMqEndpoint(middleware, zeroMqSettings), "zeromq"))

    /** An endpoint in front of an interface whose every call is answered at once: the ZeroMQ door's own part. */
    def zeroMqAnswering(): ZeroMqEndpoint.Addresses =
      addresses(
        system.systemActorOf(ZeroMqEndpoint.withInterface(new AnsweringInterface, zeroMqSettings), "zeromq-answering"))

    private val datagramSettings = DatagramDoorSettings(system).copy(port = 0)

    private def address(door: ActorRef[DatagramDoor.Command]): InetSocketAddress =
      Await.result(door.ask[InetSocketAddress](DatagramDoor.GetAddress(_)), 30.seconds)

    /** Starts the datagram door on a free loopback port; its address. */
    def datagram(): InetSocketAddress =
      address(system.systemActorOf(DatagramDoor(middleware, datagramSettings), "datagram-door"))

    /** A datagram door in front of an interface whose every call is answered at once: the datagram door's own part. */
    def datagramAnswering(): InetSocketAddress =
      address(system.systemActorOf(DatagramDoor.withInterface(new AnsweringInterface, datagramSettings),
          "datagram-door-answering"))

    def stop(): Unit = {
      system.terminate()
      Await.result(system.whenTerminated, 60.seconds)
    }
  }

  /** A `RobotInterface` without robots: every call answers `UInt(0)` at once, streams stay silent. */
  /** The gateway alone with signing on (protocol.md 6.7): a second gateway node with the team key and a plain robot
    * that signs with its robot key and checks the gateway's frames; warmed up and measured as the unsigned one.
    */
  private def signedGatewayCalls(): Array[Long] = {
    val node = new GatewayNode(signing = true)
    try {
      val key = naogateway.wire.SigningKey.fromHex(TeamKeyHex).fold(e => throw new IllegalStateException(e), identity)
      val robot = new PlainRobot(node.addresses.robots, 15.minutes, Some(key.robotKey(1)))
      try {
        node.awaitOnline(1)
        progress(s"warming up: $JitWarmup signed calls through the gateway")
        node.pings(JitWarmup)
        node.pings()
      } finally robot.close()
    } finally node.stop()
  }

  private final class AnsweringInterface extends RobotInterface {
    import scala.concurrent.Future
    import akka.{Done, NotUsed}
    import akka.stream.scaladsl.Source
    import naogateway.wire.{ActuatorGroup, Posture, RpcValue}
    import naogateway.wire.gamecontroller.GameControlData
    private val done = Future.successful(Done)
    def appName: String = "answering"
    def robots(): Future[Vector[RobotSnapshot]] = Future.successful(Vector.empty)
    def acquire(robotId: Int, groups: ActuatorGroup*): Future[Done] = done
    def release(robotId: Int, groups: ActuatorGroup*): Unit = ()
    def walk(robotId: Int, vx: Double, vy: Double, omega: Double): Future[Done] = done
    def stop(robotId: Int): Future[Done] = done
    def head(robotId: Int, pan: Double, tilt: Double): Future[Done] = done
    def arms(robotId: Int, ls: Double, le: Double, rs: Double, re: Double): Future[Done] = done
    def posture(robotId: Int, target: Posture.Target): Future[Posture] = Future.successful(target)
    def say(robotId: Int, text: String): Future[Done] = done
    def call(robotId: Int, module: String, method: String, params: RpcValue*): Future[Option[RpcValue]] =
      Future.successful(Some(RpcValue.UInt(0)))
    def send(robotId: Int, operation: robotmiddleware.Operation): Future[Done] = done
    def status(robotId: Int): Source[RobotSnapshot, NotUsed] = Source.never
    def allStatus: Source[RobotSnapshot, NotUsed] = Source.never
    def vision(robotId: Int, grid: Boolean): Source[VisionFrame, NotUsed] = Source.never
    def linkStats(robotId: Int): Source[LinkStats, NotUsed] = Source.never
    def gameState: Source[GameControlData, NotUsed] = Source.never
    def robotEvents: Source[RobotEvent, NotUsed] = Source.never
    def appEvents: Source[robotmiddleware.AppEvent, NotUsed] = Source.never
    def holds(): scala.concurrent.Future[Vector[robotmiddleware.RobotHolds]] =
      scala.concurrent.Future.successful(Vector.empty)
    def close(): Unit = ()
  }
}
