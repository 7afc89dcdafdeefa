package bench

import java.net.{InetSocketAddress, ServerSocket, Socket}

import scala.collection.immutable.ListMap
import scala.concurrent.duration._
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.ActorTestKit
import com.typesafe.config.ConfigFactory

import naogateway.integration.{BusBridgeSpec, GatewayFixture}
import naogateway.sim.bus.{Ax12, BioloidBus, BusTcpServer}
import naogateway.sim.{FirmwareSettings, RobotFirmware, SimulatedRobot, SimulatedRobotSettings}
import naogateway.testkit.TestLoopback
import naogateway.wire.{Dynamixel, MessageContents}
import naogateway.gateway.{BusBridgeServer, BusBridgeSettings}
import naogateway.api.RobotOnline

/** The robot's body (docs/protocol.md 6.8 and 6.9), measured in one run:
  *
  *   - `bus_direct_ping_*_us`: a ping of servo 1 and its status packet, a TCP client straight to the emulated bus on
  *     loopback (the emulation's own cost and the floor of any tool on a TCP port);
  *   - `bus_bridge_ping_*_us`: the same ping through the gateway's bus bridge (its TCP port, the secure stream over
  *     loopback UDP, the simulated robot's bus and back); ratio `bus_bridge_over_direct_p50`;
  *   - `servo_telemetry_bus_ms_per_period`, `servo_telemetry_bus_share`: the bus time the robot's telemetry reads take
  *     per telemetry period (one 8-byte read from address 36 per servo at 1 Mbps, 10 bits a byte, with the servo's
  *     return delay), and its share of the period;
  *   - `servo_telemetry_wifi_bytes_s_per_robot`, `servo_telemetry_wifi_team_share_6_robots`: what the telemetry adds to
  *     the simulated robot's keep-alives, in bytes per second, and for a team of 6 robots as a share of the team's WiFi
  *     budget (`naogateway.budget.team-bytes-per-second`).
  *
  * Pings are paced one at a time (the bridge has one request in flight per robot), after a warm-up; nearest-rank
  * percentiles in microseconds.
  */
object BusBench extends Benchmark {
  val name = "bus"
  override val quietSensitive = true

  private val Warmup = 300
  private val Samples = 2000
  private val robotId = 2

  private def percentile(sorted: Vector[Double], p: Double): Double =
    sorted(math.min(sorted.size - 1, math.max(0, math.ceil(p * sorted.size).toInt - 1)))

  /** `Samples` pings of servo 1 over `socket` after `Warmup`, in microseconds, sorted. */
  private def pings(socket: Socket): Vector[Double] = {
    socket.setTcpNoDelay(true)
    socket.setSoTimeout(5000)
    val ping = Dynamixel.packet(1, Dynamixel.Ping, Nil)
    val expected = Dynamixel.packet(1, 0, Nil).toVector
    val out = socket.getOutputStream
    val in = socket.getInputStream
    def one(): Double = {
      val start = System.nanoTime()
      out.write(ping)
      out.flush()
      val reply = in.readNBytes(6).toVector
      val micros = (System.nanoTime() - start) / 1e3
      require(reply == expected, s"servo 1 answered $reply")
      micros
    }
    (1 to Warmup).foreach(_ => one())
    Vector.fill(Samples)(one()).sorted
  }

  private def figures(prefix: String, sorted: Vector[Double]): ListMap[String, Double] =
    ListMap(s"${prefix}_p50_us" -> percentile(sorted, 0.5), s"${prefix}_p99_us" -> percentile(sorted, 0.99))

  /** A connection to the bridge at `port` whose ping answers (the robot's stream may still be settling). */
  private def answering(port: Int): Socket = {
    val deadline = 30.seconds.fromNow
    var found = Option.empty[Socket]
    while (found.isEmpty) {
      Try(new Socket("127.0.0.1", port)).toOption.foreach { s =>
        s.setSoTimeout(2000)
        s.getOutputStream.write(Dynamixel.packet(1, Dynamixel.Ping, Nil))
        if (Try(s.getInputStream.readNBytes(6).length).toOption.contains(6)) found = Some(s) else s.close()
      }
      if (found.isEmpty) {
        require(deadline.hasTimeLeft(), s"the bridge at $port never answered")
        Thread.sleep(200)
      }
    }
    found.get
  }

  private def bridgePings(): Vector[Double] = {
    val testKit = ActorTestKit("bus-bench")
    try {
      val f = new GatewayFixture(testKit, BusBridgeSpec.Patient)
      try {
        val base = {
          val s = new ServerSocket(0, 1, java.net.InetAddress.getLoopbackAddress)
          try s.getLocalPort - robotId
          finally s.close()
        }
        testKit.spawn(BusBridgeServer(f.gateway, BusBridgeSettings(enabled = true, basePort = base), None))
        val started = testKit.createTestProbe[SimulatedRobot.StartResult]()
        testKit.spawn(SimulatedRobot(
            SimulatedRobotSettings(FirmwareSettings(robotId), f.addresses.robots,
              bindAddress = new InetSocketAddress(TestLoopback.address(), 0), faithfulLink = false)
              .withStream(f.settings.stream),
            Some(started.ref)
          ))
        started.receiveMessage(10.seconds)
        f.awaitEvent(20.seconds) { case RobotOnline(`robotId`, _) => () }
        val socket = answering(base + robotId)
        try pings(socket)
        finally socket.close()
      } finally f.stop()
    } finally testKit.shutdownTestKit()
  }

  /** Bus time of one telemetry period: per servo one read of 8 bytes from address 36 and its status packet on the wire
    * at 1 Mbps (10 bits a byte), plus the servo's return delay (2 µs per unit of address 5); milliseconds.
    */
  def telemetryBusMillis(bus: BioloidBus): Double =
    BioloidBus.ServoIds.map { id =>
      val request = Dynamixel.packet(id, Dynamixel.Read, Seq(Ax12.PresentPosition, 8))
      val reply = bus.transact(request)._2
      require(reply.length == 14, s"servo $id answered ${reply.length} bytes")
      val returnDelayMicros = bus.tables.find(_.id == id).get.table(Ax12.ReturnDelayTime) * 2.0
      ((request.length + reply.length) * 10.0 + returnDelayMicros) / 1000.0
    }.sum

  def run(): ListMap[String, Double] = {
    val server = new BusTcpServer(BioloidBus(0L))
    val direct =
      try {
        val socket = new Socket("127.0.0.1", server.port)
        try pings(socket)
        finally socket.close()
      } finally server.close()
    val bridge = bridgePings()
    val settings = FirmwareSettings(robotId = 1)
    val robot = RobotFirmware.boot(settings, 0L)
    val busMillis = telemetryBusMillis(robot.bus)
    val keepAlive = RobotFirmware.keepAlive(robot)
    val plain = MessageContents.encodeFrame(keepAlive).toOption.get.length
    val withServos =
      MessageContents.encodeFrame(keepAlive.copy(servoTelemetry = Some(RobotFirmware.servoTelemetry(robot)))).toOption
        .get.length
    val period = settings.servoTelemetryInterval.toMillis
    val bytesPerSecond = (withServos - plain) * 1000.0 / period
    val teamBudget = ConfigFactory.load().getInt("naogateway.budget.team-bytes-per-second")
    val directFigures = figures("bus_direct_ping", direct)
    val bridgeFigures = figures("bus_bridge_ping", bridge)
    println(f"bus: ping p50 direct ${directFigures("bus_direct_ping_p50_us")}%.0f us, through the bridge " +
      f"${bridgeFigures("bus_bridge_ping_p50_us")}%.0f us; telemetry $busMillis%.1f ms of bus per $period ms, " +
      f"$bytesPerSecond%.0f B/s per robot")
    directFigures ++ bridgeFigures ++ ListMap(
      "bus_bridge_over_direct_p50" -> bridgeFigures("bus_bridge_ping_p50_us") / directFigures("bus_direct_ping_p50_us"),
      "servo_telemetry_bus_ms_per_period" -> busMillis,
      "servo_telemetry_bus_share" -> busMillis / period,
      "servo_telemetry_wifi_bytes_s_per_robot" -> bytesPerSecond,
      "servo_telemetry_wifi_team_share_6_robots" -> 6 * bytesPerSecond / teamBudget
    )
  }
}
