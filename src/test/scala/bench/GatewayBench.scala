package bench

import java.lang.management.ManagementFactory
import java.net.{InetAddress, InetSocketAddress, StandardSocketOptions}
import java.nio.ByteBuffer
import java.nio.channels.{ClosedChannelException, DatagramChannel}
import java.nio.charset.StandardCharsets
import java.nio.file.{Files, Paths}
import java.util.concurrent.{Executors, LinkedBlockingQueue, TimeUnit}
import java.util.concurrent.atomic.AtomicLong
import java.util.concurrent.locks.LockSupport

import scala.collection.immutable.ListMap
import scala.collection.mutable
import scala.concurrent.{Await, ExecutionContext, Future}
import scala.concurrent.duration._
import scala.util.Try

import akka.actor.typed.scaladsl.AskPattern._
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, ActorSystem, Behavior, Scheduler}
import akka.util.Timeout
import com.typesafe.config.{Config, ConfigFactory}
import org.slf4j.LoggerFactory

import naogateway.testkit.TestLoopback
import naogateway.access.{GatewayAccess, RobotAccess}
import naogateway.api.{
  CallResult,
  GatewayAddresses,
  GatewayEvent,
  GatewayStats,
  LinkQualityChanged,
  RobotOffline,
  RobotOnline,
  RobotStatusUpdated
}
import naogateway.gateway.{Gateway, GatewaySettings}
import naogateway.proto.Status
import naogateway.sim.network.{Impairment, LossyNetwork}
import naogateway.sim.{Fleet, FleetHandle, FleetSettings}
import naogateway.wire.{MessageContents, RpcCall}

/** The gateway on this machine, over loopback, at its default settings (reference.conf) unless a figure says otherwise:
  *
  *   - `rpc_rtt_p50_us`, `rpc_rtt_p99_us`: sequential `system.ping` calls asked of a robot's ResponseActor from outside
  *     the gateway, to a simulated robot without the CM-530/GS1500M models (faithfulLink = false), so the gateway's own
  *     path and the network are measured; `raw_udp_rtt_*`: the floor, a plain DatagramChannel ping-pong between two
  *     threads; `sim_robot_rtt_*`: the same calls framed by hand and sent by a plain DatagramChannel straight to the
  *     same kind of simulated robot, which answers that channel: the simulator's own part of `rpc_rtt_*`. All paced at
  *     one exchange per millisecond (that keeps the calls far under the team budget of 125 kB/s, which the gateway
  *     enforces and which would otherwise be what is measured), after a warm-up.
  *   - `ingest_datagrams_s`: pre-encoded keep-alives blasted by one thread from [[IngestRobots]] sockets (one robot id
  *     per socket: the gateway binds each id to the address it first came from and rejects other ids from that address)
  *     at the robot port; counted are the keep-alives the robot actors handled (their RobotStatusUpdated events), not
  *     merely received datagrams. `raw_udp_ingest_datagrams_s`: one thread's blocking receive loop fed the same way. On
  *     two cores the sending thread takes about one of them in both runs.
  *   - `recording_ingest_datagrams_s`: `ingest_datagrams_s` with `naogateway.recording` on (every datagram, each
  *     keep-alive's Status and the decisions into MCAP files in a temporary directory, deleted afterwards);
  *     `recording_ingest_ratio` = that ÷ the mean of `ingest_datagrams_s` and a second run without recording after it
  *     (`ingest_without_recording_datagrams_s`; goal ≥ 0.9).
  *   - `heartbeat_detect_ms`: from a partition of the robot's link (LossyNetwork) to RobotOffline, median of
  *     [[DetectTrials]] trials; the cut falls at a random phase of the 200 ms keep-alive period.
  *   - `heartbeat_false_offline_loss20`: RobotOffline events of one robot over 60 s at 20 % loss each way.
  *   - `fleet_*`: the largest fleet of [[FleetSizes]] (keep-alives at 5 Hz) that had no RobotOffline event over 60 s.
  *     The gateway and the simulated robots run in two actor systems of this JVM, so the gateway's part can be
  *     separated: `fleet_gateway_cpu_pct` is the CPU time of the gateway system's threads (dispatchers, scheduler,
  *     robot port reader, Akka IO selector of the GameController link) over the 60 s, in percent of one core; GC and
  *     JIT threads serve both systems and are not in it (the progress lines show them, the robots' threads and the
  *     whole process). `fleet_heap_bytes_per_robot` is the gateway's heap per robot: used heap after GC with the fleet
  *     minus used heap after GC once the gateway system is stopped (robots still running), less the empty gateway
  *     system, divided by the robots; the progress lines show the total with the simulated robots too.
  */
object GatewayBench extends Benchmark {
  val name = "gateway"
  override val quietSensitive = true

  /** The parts to run (`rtt`, `ingest`, `heartbeat`, `fleet`); all when empty. */
  var parts: Set[String] = Set.empty
  private def part(name: String)(figures: => ListMap[String, Double]): ListMap[String, Double] =
    if (parts.isEmpty || parts(name)) figures else ListMap.empty

  private[bench] val RttWarmup = 2000
  private[bench] val RttSamples = 3000
  private val RttGapNanos = 1000000L

  private val IngestRobots = 256
  // Unmeasured blast before each window. 3 s rather than 1 s: the first blast in a fresh JVM measured far below the
  // later ones (66 k/s against 118 k/s for the same blast two gateways later, load 2.8); with 3 s it still does.
  private val IngestWarmupSeconds = 3.0
  private val IngestSeconds = 5.0

  private val DetectTrials = 7
  private val LossHold = 60.seconds

  private val FleetSizes = Vector(1000, 500, 250)
  private val FleetHold = 60.seconds

  private val Loopback = InetAddress.getLoopbackAddress
  private def anyLoopbackPort = new InetSocketAddress(Loopback, 0)
  private val startedAt = new AtomicLong(System.nanoTime())

  private def progress(line: String): Unit = {
    val t = (System.nanoTime() - startedAt.get) / 1e9
    println(f"[gateway $t%6.1fs] $line")
  }

  def run(): ListMap[String, Double] = {
    startedAt.set(System.nanoTime())
    progress(s"${Runtime.getRuntime.availableProcessors} cores, load average ${loadAverage()}")
    quietLogging {
      val rtt = part("rtt")(roundTrips())
      val ingest = part("ingest")(ingestion())
      val heartbeat = part("heartbeat")(heartbeats())
      val fleet = part("fleet")(fleets())
      progress(s"done, load average ${loadAverage()}")
      rtt ++ ingest ++ heartbeat ++ fleet
    }
  }

  // ---------------------------------------------------------------------------------------------- round trips

  /** `system.ping` asked of robot 1's response actor, paced: the round trips in nanoseconds, after a warm-up. */
  private def pings(gw: GatewayNode): Array[Long] = {
    val connected = gw.connect(1)
    val ping = RpcCall("system", "ping", Vector.empty)
    implicit val scheduler: Scheduler = gw.system.scheduler
    implicit val timeout: Timeout = Timeout(5.seconds)
    def once(): Long = {
      val start = System.nanoTime()
      val answer = Await.result(connected.response.ask[CallResult](RobotAccess.Call(ping, _)), 10.seconds)
      val took = System.nanoTime() - start
      require(answer.result.isRight, s"system.ping failed: $answer")
      took
    }
    paced(RttWarmup)(() => once())
    paced(RttSamples)(() => once())
  }

  private def roundTrips(): ListMap[String, Double] = {
    val rpc = withNodes("rtt") { (gw, sim) =>
      sim.fleet(FleetSettings(gw.addresses.robots, Vector(1), faithfulLink = false,
          firstAddress = TestLoopback.address()))
      sim.sink.await(20.seconds) { case RobotOnline(1, _) => () }
      pings(gw)
    }
    progress(f"rpc rtt: p50 ${percentile(rpc, 0.50) / 1e3}%.0f us, p99 ${percentile(rpc, 0.99) / 1e3}%.0f us, " +
      f"max ${rpc.max / 1e3}%.0f us over ${rpc.length} calls")
    val raw = rawRoundTrips()
    progress(f"raw udp rtt: p50 ${percentile(raw, 0.50) / 1e3}%.0f us, p99 ${percentile(raw, 0.99) / 1e3}%.0f us, " +
      f"max ${raw.max / 1e3}%.0f us over ${raw.length} exchanges")
    val rawRobot = rawRobotRoundTrips()
    progress(f"rpc rtt to a plain-channel robot: p50 ${percentile(rawRobot, 0.50) / 1e3}%.0f us, " +
      f"p99 ${percentile(rawRobot, 0.99) / 1e3}%.0f us, max ${rawRobot.max / 1e3}%.0f us over ${rawRobot.length} calls")
    val simOnly = simulatedRobotRoundTrips()
    progress(f"simulated robot alone: p50 ${percentile(simOnly, 0.50) / 1e3}%.0f us, p99 ${percentile(simOnly, 0.99) / 1e3}%.0f us, " +
      f"max ${simOnly.max / 1e3}%.0f us over ${simOnly.length} calls")
    ListMap(
      "rpc_rtt_p50_us" -> percentile(rpc, 0.50) / 1e3,
      "rpc_rtt_p99_us" -> percentile(rpc, 0.99) / 1e3,
      "raw_udp_rtt_p50_us" -> percentile(raw, 0.50) / 1e3,
      "raw_udp_rtt_p99_us" -> percentile(raw, 0.99) / 1e3,
      "rpc_rtt_raw_robot_p50_us" -> percentile(rawRobot, 0.50) / 1e3,
      "rpc_rtt_raw_robot_p99_us" -> percentile(rawRobot, 0.99) / 1e3,
      "sim_robot_rtt_p50_us" -> percentile(simOnly, 0.50) / 1e3,
      "sim_robot_rtt_p99_us" -> percentile(simOnly, 0.99) / 1e3
    )
  }

  /** The `rpc_rtt_*` calls to a robot that is one thread on a plain DatagramChannel (keep-alives from another thread
    * every 200 ms, every request answered at once): the gateway's own round trip, without the simulator's actors.
    */
  private def rawRobotRoundTrips(): Array[Long] = withNodes("rtt-raw") { (gw, sim) =>
    val robot = new PlainRobot(gw.addresses.robots, 60.seconds)
    try {
      sim.sink.await(20.seconds) { case RobotOnline(1, _) => () }
      pings(gw)
    } finally robot.close()
  }

  /** The same `system.ping` calls, framed by hand and sent by a plain DatagramChannel straight to the same kind of
    * simulated robot, which answers that channel as its gateway: the part of `rpc_rtt_*` that is the simulator's.
    */
  private def simulatedRobotRoundTrips(): Array[Long] = {
    val client = DatagramChannel.open().bind(new InetSocketAddress(TestLoopback.address(), 0))
    val watchdog = closeAfter(60.seconds, client)
    val sim = new SimNode("sim-alone")
    try {
      val fleet =
        sim.fleet(FleetSettings(client.getLocalAddress.asInstanceOf[InetSocketAddress], Vector(1), faithfulLink = false,
            firstAddress = TestLoopback.address()))
      val robot = fleet.address(1).getOrElse(throw new IllegalStateException("the simulated robot did not start"))
      val in = ByteBuffer.allocate(2048)
      var id = 0L
      def once(): Long = {
        id += 1
        val request = RpcCall("system", "ping", Vector.empty).copy(callId = Some(id)).toProto
        val frame = MessageContents.encodeFrame(MessageContents(1, rpcRequest = Some(request))).fold(
          e => throw new IllegalStateException(e.describe), identity)
        val start = System.nanoTime()
        client.send(ByteBuffer.wrap(frame), robot)
        var answered = false
        while (!answered) { // keep-alives arrive too; only the answer to this call ends the wait
          in.clear()
          client.receive(in)
          in.flip()
          val bytes = new Array[Byte](in.remaining)
          in.get(bytes)
          answered = MessageContents.decodeFrame(bytes).exists(_._2.rpcResponse.exists(_.callId.exists(_ == id.toInt)))
        }
        System.nanoTime() - start
      }
      paced(RttWarmup)(() => once())
      paced(RttSamples)(() => once())
    } finally {
      sim.stop()
      client.close()
      watchdog.shutdownNow()
    }
  }

  /** Ping-pong of a 40-byte datagram between two blocking channels on loopback, one echo thread. */
  private[bench] def rawRoundTrips(): Array[Long] = {
    val client = DatagramChannel.open().bind(anyLoopbackPort)
    val server = DatagramChannel.open().bind(anyLoopbackPort)
    val serverAddress = server.getLocalAddress
    // Both channels close at the latest after a minute, so no thread can wait for ever on a lost datagram.
    val watchdog = closeAfter(60.seconds, client, server)
    val echo = new Thread(
      () => {
        val buffer = ByteBuffer.allocateDirect(2048)
        try {
          while (server.isOpen) {
            buffer.clear()
            val from = server.receive(buffer)
            buffer.flip()
            server.send(buffer, from)
          }
        } catch { case _: ClosedChannelException => () }
      },
      "raw-udp-echo"
    )
    echo.setDaemon(true)
    echo.start()
    try {
      val out = ByteBuffer.allocateDirect(40)
      val in = ByteBuffer.allocateDirect(2048)
      def once(): Long = {
        val start = System.nanoTime()
        out.clear()
        client.send(out, serverAddress)
        in.clear()
        client.receive(in)
        System.nanoTime() - start
      }
      paced(RttWarmup)(() => once())
      paced(RttSamples)(() => once())
    } finally {
      client.close()
      server.close()
      echo.join(5000)
      watchdog.shutdownNow()
    }
  }

  /** `n` results of `op`, each started at least [[RttGapNanos]] after the previous one started. */
  private[bench] def paced(n: Int)(op: () => Long): Array[Long] = {
    val out = new Array[Long](n)
    var i = 0
    while (i < n) {
      val start = System.nanoTime()
      out(i) = op()
      val rest = start + RttGapNanos - System.nanoTime()
      if (rest > 0) LockSupport.parkNanos(rest)
      i += 1
    }
    out
  }

  /** Nearest-rank percentile. */
  private[bench] def percentile(samples: Array[Long], p: Double): Double = {
    val sorted = samples.sorted
    sorted(math.max(0, math.ceil(p * sorted.length).toInt - 1)).toDouble
  }

  // ---------------------------------------------------------------------------------------------- ingestion

  private def keepAliveFrames(): Array[Array[Byte]] =
    (1 to IngestRobots).toArray.map { id =>
      MessageContents
        .encodeFrame(MessageContents(robotId = id,
            status = Some(Status(teamID = Some(1), activeAgent = Some("BenchAgent")))))
        .fold(e => throw new IllegalStateException(s"cannot encode a keep-alive: $e"), identity)
    }

  /** One thread sending the frames round-robin, each from its own socket, to `target` for `seconds`. */
  private final class Blaster(target: InetSocketAddress, frames: Array[Array[Byte]]) {
    // The gateway knows a robot by its IP address: each ingest robot sends from a loopback address of its own.
    private val first = naogateway.testkit.TestLoopback.block(frames.length)
    private val channels = frames.indices.toArray.map { i =>
      val base = ByteBuffer.wrap(first.getAddress).getInt
      val address = java.net.InetAddress.getByAddress(ByteBuffer.allocate(4).putInt(base + i).array())
      DatagramChannel.open().bind(new InetSocketAddress(address, 0))
    }
    private val buffers = frames.map { f =>
      val b = ByteBuffer.allocateDirect(f.length)
      b.put(f)
      b.flip()
      b
    }
    val sent = new AtomicLong

    /** One frame from every socket, so the gateway learns each robot at its address. */
    // Twice: a robot the gateway discovers is online from its second keep-alive (these robots answer no probe).
    def introduce(): Unit = for (_ <- 1 to 2; i <- channels.indices) {
      buffers(i).rewind()
      channels(i).send(buffers(i), target)
    }

    def blast(seconds: Double): Thread = {
      val thread = new Thread(
        () => {
          val end = System.nanoTime() + (seconds * 1e9).toLong
          try {
            while (System.nanoTime() < end) {
              var i = 0
              while (i < channels.length) {
                buffers(i).rewind()
                channels(i).send(buffers(i), target)
                i += 1
              }
              sent.addAndGet(channels.length.toLong)
            }
          } catch { case _: ClosedChannelException => () }
        },
        "ingest-blaster"
      )
      thread.setDaemon(true)
      thread.start()
      thread
    }

    def close(): Unit = channels.foreach(c => Try(c.close()))
  }

  /** Rate of `counter` over the measuring window of a blast that started at `start`. */
  private def windowRate(start: Long, counter: () => Long): (Double, Long) = {
    sleepUntil(start + (IngestWarmupSeconds * 1e9).toLong)
    val (t0, c0) = (System.nanoTime(), counter())
    sleepUntil(t0 + (IngestSeconds * 1e9).toLong)
    val (t1, c1) = (System.nanoTime(), counter())
    ((c1 - c0) * 1e9 / (t1 - t0), c1 - c0)
  }

  private def ingestion(): ListMap[String, Double] = {
    val frames = keepAliveFrames()
    val blastSeconds = IngestWarmupSeconds + IngestSeconds + 0.5
    val routed = routedIngest("ingest", frames, ConfigFactory.empty())
    // The same blast with recording on: every datagram, each keep-alive's Status, and the decisions into MCAP files.
    val recordingDir = Files.createTempDirectory("bench-recording")
    val recorded = routedIngest("ingest-recording", frames,
      ConfigFactory.parseString(
        s"""naogateway.recording { enabled = on, directory = "${recordingDir.toString}" }"""))
    // Off again after it: on a shared machine the load drifts, so the ratio is taken against the mean of both.
    val routedAfter = routedIngest("ingest-again", frames, ConfigFactory.empty())
    val without = (routed + routedAfter) / 2
    val recordedFiles = Files.list(recordingDir).iterator()
    var recordedBytes = 0L
    while (recordedFiles.hasNext) { val f = recordedFiles.next(); recordedBytes += Files.size(f); Files.delete(f) }
    Files.delete(recordingDir)
    progress(f"ingest with recording: ${recorded}%.0f/s against ${routed}%.0f/s and ${routedAfter}%.0f/s without " +
      f"(ratio ${recorded / without}%.3f), " +
      f"${recordedBytes / 1e6}%.1f MB recorded")
    val raw = rawIngest(frames, blastSeconds)
    ListMap(
      "ingest_datagrams_s" -> routed,
      "raw_udp_ingest_datagrams_s" -> raw,
      "recording_ingest_datagrams_s" -> recorded,
      "ingest_without_recording_datagrams_s" -> without,
      "recording_ingest_ratio" -> recorded / without
    )
  }

  /** Keep-alives the robot actors handled per second under the blast, with `gatewayConfig` over the defaults. */
  private def routedIngest(tag: String, frames: Array[Array[Byte]], gatewayConfig: Config): Double = {
    val blastSeconds = IngestWarmupSeconds + IngestSeconds + 0.5
    withNodes(tag, gatewayConfig, eventsOnPortLoop = true) { (gw, sim) =>
      val blaster = new Blaster(gw.addresses.robots, frames)
      try {
        blaster.introduce()
        val online = mutable.Set.empty[Int]
        val deadline = 20.seconds.fromNow
        while (online.size < IngestRobots && deadline.hasTimeLeft())
          sim.sink.poll(deadline.timeLeft.max(1.milli)).foreach { case (_, e) =>
            e match { case RobotOnline(id, _) => online += id; case _ => () }
          }
        require(online.size == IngestRobots, s"only ${online.size} of $IngestRobots ingest robots came online")
        val before = gw.stats()
        val start = System.nanoTime()
        val thread = blaster.blast(blastSeconds)
        val sentAtStart = blaster.sent.get
        val gatewayCpu = new ThreadCpu(s"${gw.system.name}-")
        val handledAtStart = sim.sink.statusUpdates.get
        var handledAtSample = handledAtStart
        val (rate, counted) = windowRate(start,
          () => {
            gatewayCpu.sample()
            handledAtSample = sim.sink.statusUpdates.get
            handledAtSample
          })
        val window = System.nanoTime() - start
        thread.join()
        progress(
          s"ingest: CPU of the gateway's threads over the blast in % of one core: ${gatewayCpu.breakdown(window)}")
        // What load does not move: the bytes the threads allocated for each keep-alive handled.
        progress(s"$tag: bytes allocated per keep-alive handled, by kind of thread: " +
          gatewayCpu.allocatedPer(handledAtSample - handledAtStart))
        val sentRate = (blaster.sent.get - sentAtStart) / blastSeconds
        val after = gw.stats()
        val waited = (System.nanoTime() - start) / 1e9 - blastSeconds
        progress(
          f"$tag: sent ${sentRate}%.0f/s, routed ${rate}%.0f/s ($counted keep-alives in ${IngestSeconds}%.0f s); " +
            f"gateway actor had taken ${after.datagramsIn - before.datagramsIn} datagrams ${waited}%.1f s after the blast, " +
            s"rejected ${after.rejected.values.sum - before.rejected.values.sum}, status events so far ${sim.sink.statusUpdates.get}" +
            (if (after.recording.enabled)
               s"; recording: ${after.recording.messages} messages, ${after.recording.dropped} dropped"
             else ""))
        rate
      } finally blaster.close()
    }
  }

  /** One thread's plain receive loop under the same blast: the floor. */
  private def rawIngest(frames: Array[Array[Byte]], blastSeconds: Double): Double = {
    val receiver = DatagramChannel.open().bind(anyLoopbackPort)
    // The same receive buffer the gateway's robot link asks for.
    receiver.setOption[Integer](StandardSocketOptions.SO_RCVBUF, 4 * 1024 * 1024)
    val watchdog = closeAfter(60.seconds, receiver)
    val received = new AtomicLong
    val loop = new Thread(
      () => {
        val buffer = ByteBuffer.allocateDirect(2048)
        try {
          while (receiver.isOpen) {
            buffer.clear()
            if (receiver.receive(buffer) != null) received.lazySet(received.get + 1)
          }
        } catch { case _: ClosedChannelException => () }
      },
      "raw-udp-receiver"
    )
    loop.setDaemon(true)
    loop.start()
    val blaster = new Blaster(receiver.getLocalAddress.asInstanceOf[InetSocketAddress], frames)
    try {
      val start = System.nanoTime()
      val thread = blaster.blast(blastSeconds)
      val (rate, counted) = windowRate(start, () => received.get)
      thread.join()
      progress(
        f"raw udp ingest: sent ${blaster.sent.get / blastSeconds}%.0f/s, received ${rate}%.0f/s ($counted in ${IngestSeconds}%.0f s)")
      rate
    } finally {
      blaster.close()
      receiver.close()
      loop.join(5000)
      watchdog.shutdownNow()
    }
  }

  // ---------------------------------------------------------------------------------------------- heartbeat

  private def heartbeats(): ListMap[String, Double] = {
    // The loss run takes a minute and barely loads the machine; the detection trials run meanwhile on their own nodes.
    val background = Executors.newSingleThreadExecutor()
    try {
      val loss = Future(falseOfflineAtLoss())(ExecutionContext.fromExecutor(background))
      val detection = detectionTrials()
      val offline = Await.result(loss, LossHold + 2.minutes)
      ListMap("heartbeat_detect_ms" -> detection, "heartbeat_false_offline_loss20" -> offline.toDouble)
    } finally background.shutdown()
  }

  private def detectionTrials(): Double = withNodes("detect") { (gw, sim) =>
    val network = LossyNetwork.start(seed = 7)
    try {
      val proxy = network.addProxy(gw.addresses.robots, TestLoopback.address())
      sim.fleet(FleetSettings(proxy.clientSide, Vector(1), faithfulLink = false, firstAddress = TestLoopback.address()))
      sim.sink.await(20.seconds) { case RobotOnline(1, _) => () }
      val random = new scala.util.Random(7)
      val times = (1 to DetectTrials).map { trial =>
        // At least a second online, then a cut at a random phase of the keep-alive period.
        Thread.sleep(1000L + random.nextInt(200))
        network.partition(proxy, on = true)
        val cut = System.nanoTime()
        val (at, reason) = sim.sink.await(10.seconds) { case RobotOffline(1, reason) => reason }
        network.partition(proxy, on = false)
        sim.sink.await(10.seconds) { case RobotOnline(1, _) => () }
        val ms = (at - cut) / 1e6
        progress(f"heartbeat detection trial $trial: $ms%.0f ms ($reason)")
        ms
      }
      val sorted = times.sorted
      progress(
        f"heartbeat detection: median ${sorted(sorted.size / 2)}%.0f ms, min ${sorted.head}%.0f, max ${sorted.last}%.0f " +
          s"(configured worst case from the last keep-alive: 400 ms quiet + 3 x 150 ms probes)")
      sorted(sorted.size / 2)
    } finally network.stop()
  }

  private def falseOfflineAtLoss(): Int = withNodes("loss20") { (gw, sim) =>
    val network = LossyNetwork.start(seed = 20)
    try {
      val lossy = Impairment(loss = 0.2)
      val proxy = network.addProxy(gw.addresses.robots, TestLoopback.address(), uplink = lossy, downlink = lossy)
      sim.fleet(FleetSettings(proxy.clientSide, Vector(1), faithfulLink = false, firstAddress = TestLoopback.address()))
      sim.sink.await(20.seconds) { case RobotOnline(1, _) => () }
      val statusBefore = sim.sink.statusUpdates.get
      val end = LossHold.fromNow
      var offline, online, quality = 0
      while (end.hasTimeLeft())
        sim.sink.poll(end.timeLeft.max(1.milli)).foreach {
          case (_, RobotOffline(1, reason)) =>
            offline += 1
            progress(s"loss 20 %: false offline event $offline ($reason)")
          case (_, RobotOnline(1, _))        => online += 1
          case (_, LinkQualityChanged(1, _)) => quality += 1
          case _                             => ()
        }
      val c = network.stats(proxy)
      progress(
        s"loss 20 % over ${LossHold.toSeconds} s: $offline offline, $online back online, $quality quality changes, " +
          s"${sim.sink.statusUpdates.get - statusBefore} keep-alives arrived; proxy uplink ${c.uplink.forwarded}/${c.uplink.received} " +
          s"forwarded, downlink ${c.downlink.forwarded}/${c.downlink.received}")
      offline
    } finally network.stop()
  }

  // ---------------------------------------------------------------------------------------------- fleet

  private final case class FleetRun(robots: Int, held: Boolean, falseOffline: Int, gatewayCpuPct: Double,
      heapPerRobot: Double)

  private def fleets(): ListMap[String, Double] = {
    var runs = Vector.empty[FleetRun]
    val it = FleetSizes.iterator
    while (it.hasNext && !runs.lastOption.exists(_.held)) runs :+= fleet(it.next())
    // The largest that held; when none did, the smallest tried, whose false offline events then show the miss.
    val chosen = runs.find(_.held).getOrElse(runs.last)
    ListMap(
      "fleet_robots" -> chosen.robots.toDouble,
      "fleet_gateway_cpu_pct" -> chosen.gatewayCpuPct,
      "fleet_heap_bytes_per_robot" -> chosen.heapPerRobot,
      "fleet_false_offline" -> chosen.falseOffline.toDouble
    )
  }

  private def fleet(n: Int): FleetRun = {
    progress(s"fleet of $n: starting (load average ${loadAverage()})")
    val sim = new SimNode(s"sim-fleet$n")
    try {
      val emptyBase = usedHeapAfterGc()
      val gw = new GatewayNode(s"gw-fleet$n")
      var gatewayStopped = false
      try {
        gw.subscribe(sim.sinkRef)
        val gatewayBase = usedHeapAfterGc()
        val ids = (1 to n).toVector
        val handle = sim.fleet(FleetSettings(gw.addresses.robots, ids, faithfulLink = false,
            firstAddress = TestLoopback.block(n), startTimeout = 90.seconds,
            stopTimeout = 60.seconds))
        try {
          val online = mutable.Set.empty[Int]
          var startupOffline = 0
          val deadline = 60.seconds.fromNow
          while (online.size < n && deadline.hasTimeLeft())
            sim.sink.poll(deadline.timeLeft.max(1.milli)).foreach {
              case (_, RobotOnline(id, _)) => online += id
              case (_, RobotOffline(_, _)) => startupOffline += 1
              case _                       => ()
            }
          if (online.size < n) {
            progress(s"fleet of $n: only ${online.size} robots online after 60 s; not held")
            FleetRun(n, held = false, n - online.size + startupOffline, Double.NaN, Double.NaN)
          } else {
            if (startupOffline > 0) progress(s"fleet of $n: $startupOffline offline event(s) while the fleet came up")
            progress(s"fleet of $n: all online; holding ${FleetHold.toSeconds} s")
            val gatewayCpu = new ThreadCpu(s"${gw.system.name}-")
            val robotsCpu = new ThreadCpu(s"${sim.system.name}-")
            val os = ManagementFactory.getOperatingSystemMXBean.asInstanceOf[com.sun.management.OperatingSystemMXBean]
            val process0 = os.getProcessCpuTime
            val status0 = sim.sink.statusUpdates.get
            val t0 = System.nanoTime()
            var offline = 0
            var nextReport = t0 + 10000000000L
            val end = t0 + FleetHold.toNanos
            while (System.nanoTime() < end && offline == 0) {
              sim.sink.poll(100.millis).foreach {
                case (_, RobotOffline(id, reason)) =>
                  offline += 1
                  progress(s"fleet of $n: robot $id went offline ($reason)")
                case _ => ()
              }
              gatewayCpu.sample()
              robotsCpu.sample()
              if (System.nanoTime() >= nextReport) {
                val s = (System.nanoTime() - t0) / 1e9
                progress(
                  f"fleet of $n: $s%.0f s, ${(sim.sink.statusUpdates.get - status0) / s}%.0f keep-alives/s routed, " +
                    f"gateway threads ${gatewayCpu.total / 1e7 / s}%.1f %% of a core, no offline")
                nextReport += 10000000000L
              }
            }
            val wall = System.nanoTime() - t0
            gatewayCpu.sample()
            robotsCpu.sample()
            val process = os.getProcessCpuTime - process0
            val keepAlives = (sim.sink.statusUpdates.get - status0) * 1e9 / wall
            val gatewayPct = gatewayCpu.total * 100.0 / wall
            val robotsPct = robotsCpu.total * 100.0 / wall
            val processPct = process * 100.0 / wall
            if (offline > 0) {
              progress(
                f"fleet of $n: offline after ${wall / 1e9}%.1f s; not held (gateway threads $gatewayPct%.1f %%, " +
                  f"robots $robotsPct%.1f %%, whole process $processPct%.1f %% of a core)")
              FleetRun(n, held = false, offline, gatewayPct, Double.NaN)
            } else {
              val withFleet = usedHeapAfterGc()
              gw.stop()
              gatewayStopped = true
              val robotsOnly = usedHeapAfterGc()
              val gatewayPerRobot = ((withFleet - robotsOnly) - (gatewayBase - emptyBase)).toDouble / n
              val totalPerRobot = (withFleet - gatewayBase).toDouble / n
              progress(
                f"fleet of $n held ${wall / 1e9}%.0f s: $keepAlives%.0f keep-alives/s routed; CPU in %% of one core: " +
                  f"gateway threads $gatewayPct%.1f, simulated robots' threads $robotsPct%.1f, " +
                  f"whole process $processPct%.1f (rest: GC, JIT, bench ${processPct - gatewayPct - robotsPct}%.1f)")
              progress(s"fleet of $n: gateway threads by kind, % of one core: ${gatewayCpu.breakdown(wall)}")
              progress(
                f"fleet of $n heap after GC: gateway $gatewayPerRobot%.0f B/robot; gateway and simulated robots together " +
                  f"$totalPerRobot%.0f B/robot (empty ${emptyBase >> 20} MiB, +gateway ${gatewayBase >> 20} MiB, " +
                  f"+fleet ${withFleet >> 20} MiB, fleet without gateway ${robotsOnly >> 20} MiB)")
              FleetRun(n, held = true, 0, gatewayPct, gatewayPerRobot)
            }
          }
        } finally Try(Await.result(handle.stop(), 90.seconds))
      } finally if (!gatewayStopped) gw.stop()
    } finally sim.stop()
  }

  /** CPU time of the live threads whose names start with `prefix`, since this meter was made. */
  private final class ThreadCpu(prefix: String) {
    private val mx = ManagementFactory.getThreadMXBean
    private val base = mutable.LongMap.empty[Long]
    private val last = mutable.LongMap.empty[Long]
    private val names = mutable.LongMap.empty[String]
    // Bytes allocated by each thread, at the first scan and at the latest (HotSpot's ThreadMXBean; empty without it).
    private val allocBase = mutable.LongMap.empty[Long]
    private val allocLast = mutable.LongMap.empty[Long]
    scan().foreach { case (id, t) => base(id) = t; last(id) = t }
    allocBase ++= allocLast

    private def allocated(id: Long): Unit = mx match {
      case hs: com.sun.management.ThreadMXBean =>
        val b = hs.getThreadAllocatedBytes(id)
        if (b >= 0) allocLast(id) = b
      case _ => ()
    }

    /** Bytes allocated per `n` (e.g. keep-alives handled) since the start, per kind of thread, busiest first. */
    def allocatedPer(n: Long): String =
      perKind(allocLast, allocBase)((kind, bytes) => f"$kind ${bytes.toDouble / math.max(1L, n)}%.0f")

    // Each thread's growth since its base summed by kind of thread, busiest first, each shown by `show`.
    private def perKind(now: collection.Map[Long, Long], base: collection.Map[Long, Long])(
        show: (String, Long) => String): String =
      now.iterator
        .map { case (id, v) => names(id) -> (v - base.getOrElse(id, 0L)) }
        .toVector
        .groupMapReduce(_._1)(_._2)(_ + _)
        .toVector
        .sortBy(-_._2)
        .map { case (kind, v) => show(kind, v) }
        .mkString(", ")

    private def scan(): Iterator[(Long, Long)] = {
      val ids = mx.getAllThreadIds
      mx.getThreadInfo(ids).iterator.filter(i => i != null && i.getThreadName.startsWith(prefix)).flatMap { i =>
        val t = mx.getThreadCpuTime(i.getThreadId)
        names(i.getThreadId) = i.getThreadName.stripPrefix(prefix).replaceAll("-[0-9]+$", "")
        allocated(i.getThreadId)
        if (t >= 0) Some(i.getThreadId -> t) else None
      }
    }

    /** Takes note of every thread now; a thread that ends between two samples loses its last interval. */
    def sample(): Unit = scan().foreach { case (id, t) => last(id) = t }

    def total: Long = last.iterator.map { case (id, t) => t - base.getOrElse(id, 0L) }.sum

    /** Percent of one core over `wallNanos` per kind of thread (dispatcher, scheduler, IO selector), busiest first. */
    def breakdown(wallNanos: Long): String =
      perKind(last, base)((kind, nanos) => f"$kind ${nanos * 100.0 / wallNanos}%.1f")
  }

  // ---------------------------------------------------------------------------------------------- nodes

  /** Loopback, an OS-chosen robot port, no GameController listener; everything else from reference.conf. */
  private def nodeConfig: Config = ConfigFactory.load(
    ConfigFactory.parseString(
      """naogateway.link.bind-address = "127.0.0.1"
        |naogateway.link.robot-port = 0
        |naogateway.game-controller.enabled = off
        |naogateway.discovery.max-robots = 1000
        |akka.loglevel = "WARNING"
        |""".stripMargin
    )
  )

  /** A gateway as the guardian of its own actor system. */
  private final class GatewayNode(systemName: String, extra: Config = ConfigFactory.empty()) {
    private val config = extra.withFallback(nodeConfig)
    val system: ActorSystem[GatewayAccess.Command] =
      ActorSystem(Gateway(GatewaySettings.fromConfig(config.getConfig("naogateway"))), systemName, config)
    private implicit val scheduler: Scheduler = system.scheduler
    private implicit val timeout: Timeout = Timeout(30.seconds)
    val addresses: GatewayAddresses = Await.result(system.ask(GatewayAccess.GetAddresses(_)), 30.seconds)

    def subscribe(subscriber: ActorRef[GatewayEvent]): Unit = system ! GatewayAccess.Subscribe(subscriber)

    def connect(robotId: Int): RobotAccess.Opened = {
      val robot = Await
        .result(system.ask[Option[ActorRef[RobotAccess.Command]]](GatewayAccess.GetRobotAccess(robotId, _)), 30.seconds)
        .getOrElse(throw new IllegalStateException(s"the gateway does not know robot $robotId"))
      Await.result(robot.ask[RobotAccess.Opened](RobotAccess.Open(_)), 30.seconds)
    }

    def stats(): GatewayStats = Await.result(system.ask(GatewayAccess.GetStats(_)), 30.seconds)

    def stop(): Unit = {
      system.terminate()
      Await.result(system.whenTerminated, 60.seconds)
    }
  }

  /** The simulated robots' actor system, with the subscriber that receives the gateway's events. */
  private final class SimNode(systemName: String) {
    val system: ActorSystem[Nothing] = ActorSystem[Nothing](Behaviors.empty, systemName, nodeConfig)
    val sink = new EventSink
    val sinkRef: ActorRef[GatewayEvent] = system.systemActorOf(sink.behavior, "gateway-events")

    def fleet(settings: FleetSettings): FleetHandle =
      Await.result(Fleet.start(system, settings), settings.startTimeout + 10.seconds)

    def stop(): Unit = {
      system.terminate()
      Await.result(system.whenTerminated, 60.seconds)
    }
  }

  /** A gateway subscribed to the events sink of a robots' node; both stop afterwards. With `eventsOnPortLoop` the
    * sink's actor runs in the gateway's system on the port loop, where the package runs the middleware, the robot
    * actors' subscriber (launcher.conf: `robotmiddleware.dispatcher`): an event is then a task on the same thread, not
    * a message that wakes another system's pool.
    */
  private def withNodes[T](tag: String, gatewayConfig: Config = ConfigFactory.empty(),
      eventsOnPortLoop: Boolean =
        false)(body: (GatewayNode, SimNode) => T): T = {
    val sim = new SimNode(s"sim-$tag")
    try {
      val gw = new GatewayNode(s"gw-$tag", gatewayConfig)
      try {
        if (!eventsOnPortLoop) gw.subscribe(sim.sinkRef)
        else gw.subscribe(gw.system.systemActorOf(sim.sink.behavior, "gateway-events", Gateway.RobotDispatcher))
        body(gw, sim)
      } finally gw.stop()
    } finally sim.stop()
  }

  /** Counts status updates; queues every other event with the time it arrived. */
  private final class EventSink {
    val statusUpdates = new AtomicLong
    private val queue = new LinkedBlockingQueue[(Long, GatewayEvent)]()

    val behavior: Behavior[GatewayEvent] = Behaviors.receiveMessage { event =>
      event match {
        case _: RobotStatusUpdated => statusUpdates.incrementAndGet()
        case other                 => queue.put(System.nanoTime() -> other)
      }
      Behaviors.same
    }

    def poll(within: FiniteDuration): Option[(Long, GatewayEvent)] =
      Option(queue.poll(within.toNanos, TimeUnit.NANOSECONDS))

    /** The arrival time and value of the first event matching `pf`, skipping others. */
    def await[T](within: FiniteDuration)(pf: PartialFunction[GatewayEvent, T]): (Long, T) = {
      val deadline = within.fromNow
      var found: Option[(Long, T)] = None
      while (found.isEmpty) {
        if (deadline.isOverdue()) throw new IllegalStateException(s"no matching gateway event within $within")
        poll(deadline.timeLeft.max(1.milli)).foreach { case (at, e) => found = pf.lift(e).map(at -> _) }
      }
      found.get
    }
  }

  // ---------------------------------------------------------------------------------------------- helpers

  private def usedHeapAfterGc(): Long = {
    System.gc()
    Thread.sleep(200)
    System.gc()
    ManagementFactory.getMemoryMXBean.getHeapMemoryUsage.getUsed
  }

  private def sleepUntil(at: Long): Unit = {
    val rest = at - System.nanoTime()
    if (rest > 0) TimeUnit.NANOSECONDS.sleep(rest)
  }

  /** Closes the channels after `delay` unless shut down first: a bound on every blocking receive. */
  private[bench] def closeAfter(delay: FiniteDuration, channels: DatagramChannel*) = {
    val timer = Executors.newSingleThreadScheduledExecutor { (r: Runnable) =>
      val t = new Thread(r, "bench-watchdog")
      t.setDaemon(true)
      t
    }
    timer.schedule((() => channels.foreach(c => Try(c.close()))): Runnable, delay.toMillis, TimeUnit.MILLISECONDS)
    timer
  }

  private[bench] def loadAverage(): String =
    Try(new String(Files.readAllBytes(Paths.get("/proc/loadavg")), StandardCharsets.US_ASCII).split(' ').take(3).mkString(
        " "))
      .getOrElse("unknown")

  /** The test logging captures every event in memory for the whole run; the bench keeps only warnings and errors. */
  private[bench] def quietLogging[T](body: => T): T =
    LoggerFactory.getLogger(org.slf4j.Logger.ROOT_LOGGER_NAME) match {
      case root: ch.qos.logback.classic.Logger =>
        val before = root.getLevel
        root.setLevel(ch.qos.logback.classic.Level.WARN)
        try body
        finally root.setLevel(before)
      case _ => body
    }
}
