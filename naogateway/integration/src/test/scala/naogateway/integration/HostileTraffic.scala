package naogateway.integration

import java.net.{InetAddress, InetSocketAddress}
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel
import java.util.concurrent.atomic.AtomicLong

import scala.concurrent.duration._
import scala.util.Random

import ch.qos.logback.classic.spi.ILoggingEvent
import ch.qos.logback.classic.{Level, Logger, LoggerContext}
import ch.qos.logback.core.AppenderBase
import org.slf4j.LoggerFactory

import naogateway.proto.{RobotHealth, Status}
import naogateway.wire.gamecontroller.{GameControllerCodec, GameState}
import naogateway.wire.{HeaderForm, MessageContents}
import naogateway.testkit.GameControllerCodecSupport
import naogateway.testkit.TestLoopback

/** What a stranger on the field's WiFi can send a gateway, written from docs/protocol.md: random bytes, mutated frames,
  * keep-alives with invented robot ids or forged contents, and GameController packets. Shared by the hostile-network
  * spec and the `flood` benchmark. Everything goes to loopback addresses only, in bounded loops.
  */
object HostileTraffic {

  /** The two real robots of a flood: robots 1 and 2 started on `f`'s gateway, once both are online. Answers robot 1's
    * receive address, whose IP a forger then sends from.
    */
  def twoRobotsOnline(f: GatewayFixture): InetSocketAddress = {
    val (_, at1) = f.robot(1)
    f.robot(2)
    var online = Set.empty[Int]
    while (online.size < 2) online += f.awaitEvent(10.seconds) { case naogateway.api.RobotOnline(id @ (1 | 2), _) =>
      id
    }
    at1
  }

  /** A keep-alive of `robotId` as the simulated firmware sends it, with the values a forger chooses. */
  def keepAlive(
      robotId: Int, bootId: Option[Int] = Some(1), uptimeMillis: Long = 1000L, battery: Float = 12.4f): Array[Byte] =
    MessageContents.encodeFrame(
      MessageContents(
        robotId,
        status = Some(Status(timestamp = Some(uptimeMillis), teamID = Some(1), activeAgent = Some("forged"))),
        robotHealth =
          Some(RobotHealth(batteryVoltage = Some(battery), posture = Some("stand"), uptimeMs = Some(uptimeMillis.toInt),
              bootId = bootId))
      ),
      HeaderForm.Legacy
    ).toOption.get

  /** A GameController control packet saying `state`, as any sender can make one. */
  def gameControllerPacket(state: GameState): Array[Byte] =
    GameControllerCodec.encodeControl(GameControllerCodecSupport.playing(teamNumber = 1).copy(gameState = state))
      .toOption.get

  /** `n` random datagrams, 0 to 1500 bytes, some starting like a frame (`00 2A`) or a GameController packet (`RGme`).
    */
  def randomDatagrams(n: Int, random: Random): Iterator[Array[Byte]] = Iterator.fill(n) {
    val bytes = Array.fill[Byte](random.nextInt(1501))(0)
    random.nextBytes(bytes)
    random.nextInt(3) match {
      case 0 if bytes.length >= 2 => bytes(0) = 0; bytes(1) = 0x2a
      case 1 if bytes.length >= 4 => "RGme".getBytes("US-ASCII").copyToArray(bytes)
      case _                      => ()
    }
    bytes
  }

  /** `n` mutations of valid `frame`: bytes flipped, cut short, grown, or the length field lying. */
  def mutatedFrames(frame: Array[Byte], n: Int, random: Random): Iterator[Array[Byte]] = Iterator.fill(n) {
    val f = frame.clone()
    random.nextInt(4) match {
      case 0 =>
        (1 to 1 + random.nextInt(4)).foreach(_ => f(random.nextInt(f.length)) = random.nextInt(256).toByte)
        f
      case 1 => f.take(random.nextInt(f.length))
      case 2 => f ++ Array.fill[Byte](1 + random.nextInt(200))(random.nextInt(256).toByte)
      case _ =>
        if (f.length > 7) f(7) = (f(7) + 1 + random.nextInt(50)).toByte
        f
    }
  }

  /** Loopback addresses `first`, `first` + 1, ... (as TestLoopback hands out blocks). */
  def addresses(first: InetAddress, n: Int): Vector[InetAddress] = (0 until n).toVector.map { i =>
    InetAddress.getByAddress(ByteBuffer.allocate(4).putInt(ByteBuffer.wrap(first.getAddress).getInt + i).array())
  }

  /** Sockets of a stranger, one per address; `send` paces itself so the kernel's receive buffer is not the test. */
  final class Sender(from: Vector[InetAddress]) extends AutoCloseable {
    private val channels = from.map(a => DatagramChannel.open().bind(new InetSocketAddress(a, 0)))
    private var sent = 0L

    /** Sends `bytes` to `to` from the `i`-th socket (modulo their number); every 500 datagrams it pauses 5 ms. */
    def send(bytes: Array[Byte], to: InetSocketAddress, i: Int = 0): Unit = {
      channels(Math.floorMod(i, channels.size)).send(ByteBuffer.wrap(bytes), to)
      sent += 1
      if (sent % 500 == 0) Thread.sleep(5)
    }

    /** Datagrams sent so far. */
    def count: Long = sent

    def close(): Unit = channels.foreach(_.close())
  }

  /** Counts the log events at INFO and above while it is installed (on the root logger), and raises the `naogateway`
    * loggers to INFO meanwhile: their debug lines name each refused datagram by design, the operator's log does not.
    */
  final class LogLines extends AutoCloseable {
    private val context = LoggerFactory.getILoggerFactory.asInstanceOf[LoggerContext]
    private val root = context.getLogger(org.slf4j.Logger.ROOT_LOGGER_NAME)
    private val gateway: Logger = context.getLogger("naogateway")
    private val levelBefore = gateway.getLevel
    private val counted = new AtomicLong
    private val byTemplate = new java.util.concurrent.ConcurrentHashMap[String, AtomicLong]()
    private val appender = new AppenderBase[ILoggingEvent] {
      override def append(e: ILoggingEvent): Unit =
        if (e.getLevel.isGreaterOrEqual(Level.INFO)) {
          counted.incrementAndGet()
          // Templates, not formatted lines: a bounded set however many lines there are.
          if (byTemplate.size < 200 || byTemplate.containsKey(e.getMessage))
            byTemplate.computeIfAbsent(e.getMessage, _ => new AtomicLong).incrementAndGet()
          ()
        }
    }
    appender.setContext(context)
    appender.setName(s"count-${System.nanoTime()}")
    appender.start()
    gateway.setLevel(Level.INFO)
    root.addAppender(appender)

    /** Lines logged since installed. */
    def count: Long = counted.get

    /** The most frequent message templates and their counts, for a report. */
    def top(n: Int): Vector[(String, Long)] = {
      import scala.jdk.CollectionConverters._
      byTemplate.asScala.toVector.map { case (k, v) => k -> v.get }.sortBy(-_._2).take(n)
    }

    def close(): Unit = {
      root.detachAppender(appender)
      appender.stop()
      gateway.setLevel(levelBefore)
    }
  }

  /** What a flood sent, and the most robot actors the gateway had while it ran. */
  final case class FloodResult(datagrams: Long, robotActorsMax: Int, gameControllerPackets: Int)

  /** `rounds` rounds of what a stranger can send to the gateway of `f`, `scale` times this much each round: 1000 random
    * datagrams and 1000 mutations of robot 1's keep-alive from 4 addresses; 150 keep-alives with invented robot ids
    * from one socket and 100 from `50 x scale` addresses (at most 200); 25 GameController packets saying PLAYING or
    * READY from an address the gateway must not trust; and two odd keep-alives from robot 1's own address `robot1`
    * (another bootId, a clock far ahead, a flat battery), never three in a row. Between rounds it pauses 150-250 ms and
    * samples the gateway's robot count.
    */
  def flood(f: GatewayFixture, robot1: InetAddress, rounds: Int, scale: Int, seed: Long): FloodResult = {
    val stranger = new Sender(addresses(TestLoopback.block(4, 0), 4))
    val spread = math.min(200, 50 * scale)
    val idFlooders = new Sender(addresses(TestLoopback.block(spread, 0), spread))
    val lonely = new Sender(Vector(TestLoopback.address(0)))
    val forger = new Sender(Vector(robot1))
    val random = new Random(seed)
    val robotPort = f.addresses.robots
    val gcPort = f.addresses.gameController.get
    val frame = keepAlive(1)
    var robotsMax = 0
    var nextId = 1000
    var gcSent = 0
    try {
      (0 until rounds).foreach { round =>
        randomDatagrams(1000 * scale, random).zipWithIndex.foreach { case (d, i) => stranger.send(d, robotPort, i) }
        mutatedFrames(frame, 1000 * scale, random).zipWithIndex.foreach { case (d, i) =>
          stranger.send(d, robotPort, i)
        }
        (0 until 150 * scale).foreach { _ => lonely.send(keepAlive(nextId), robotPort); nextId += 1 }
        (0 until 100 * scale).foreach { i => idFlooders.send(keepAlive(nextId), robotPort, i); nextId += 1 }
        (0 until 25 * scale).foreach { i =>
          stranger.send(gameControllerPacket(if (i % 2 == 0) GameState.Playing else GameState.Ready), gcPort, i)
          gcSent += 1
        }
        forger.send(keepAlive(1, Some(random.nextInt(100) + 2), random.nextInt(5000).toLong, 10.0f), robotPort)
        forger.send(keepAlive(1, Some(1), 1000000000L + random.nextInt(1000000), 10.0f), robotPort)
        robotsMax = math.max(robotsMax, f.stats().robots)
        Thread.sleep(if (round % 2 == 0) 250 else 150)
        robotsMax = math.max(robotsMax, f.stats().robots)
      }
    } finally Seq(stranger, idFlooders, lonely, forger).foreach(_.close())
    FloodResult(stranger.count + idFlooders.count + lonely.count + forger.count, robotsMax, gcSent)
  }

  /** Heap in use after a full collection, in bytes (a rough figure: enough for a generous bound). */
  def usedHeapAfterGc(): Long = {
    val rt = Runtime.getRuntime
    (1 to 3).foreach { _ =>
      System.gc()
      Thread.sleep(100)
    }
    rt.totalMemory() - rt.freeMemory()
  }
}
