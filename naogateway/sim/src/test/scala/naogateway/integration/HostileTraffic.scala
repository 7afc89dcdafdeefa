package naogateway.integration

import java.net.{InetAddress, InetSocketAddress}
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel
import java.util.concurrent.atomic.AtomicLong

import scala.util.Random

import ch.qos.logback.classic.spi.ILoggingEvent
import ch.qos.logback.classic.{Level, Logger, LoggerContext}
import ch.qos.logback.core.AppenderBase
import org.slf4j.LoggerFactory

import naogateway.proto.{RobotHealth, Status}
import naogateway.wire.gamecontroller.{GameControllerCodec, GameState}
import naogateway.wire.{HeaderForm, MessageContents}

/**
 * What a stranger on the field's WiFi can send a gateway, written from docs/protocol.md: random bytes, mutated frames,
 * keep-alives with invented robot ids or forged contents, and GameController packets. Shared by the hostile-network
 * spec and the `flood` benchmark. Everything goes to loopback addresses only, in bounded loops.
 */
object HostileTraffic {

  /** A keep-alive of `robotId` as the simulated firmware sends it, with the values a forger chooses. */
  def keepAlive(robotId: Int, bootId: Option[Int] = Some(1), uptimeMillis: Long = 1000L, battery: Float = 12.4f): Array[Byte] =
    MessageContents.encodeFrame(
      MessageContents(robotId, status = Some(Status(timestamp = Some(uptimeMillis), teamID = Some(1), activeAgent = Some("forged"))),
        robotHealth = Some(RobotHealth(batteryVoltage = Some(battery), posture = Some("stand"), uptimeMs = Some(uptimeMillis.toInt),
          bootId = bootId))),
      HeaderForm.Legacy
    ).toOption.get

  /** A GameController control packet saying `state`, as any sender can make one. */
  def gameControllerPacket(state: GameState): Array[Byte] =
    GameControllerCodec.encodeControl(GameControllerCodecSupport.playing(teamNumber = 1).copy(gameState = state)).toOption.get

  /** `n` random datagrams, 0 to 1500 bytes, some starting like a frame (`00 2A`) or a GameController packet (`RGme`). */
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

  /**
   * Counts the log events at INFO and above while it is installed (on the root logger), and raises the `naogateway`
   * loggers to INFO meanwhile: their debug lines name each refused datagram by design, the operator's log does not.
   */
  final class LogLines extends AutoCloseable {
    private val context = LoggerFactory.getILoggerFactory.asInstanceOf[LoggerContext]
    private val root = context.getLogger(org.slf4j.Logger.ROOT_LOGGER_NAME)
    private val gateway: Logger = context.getLogger("naogateway")
    private val levelBefore = gateway.getLevel
    private val counted = new AtomicLong
    private val appender = new AppenderBase[ILoggingEvent] {
      override def append(e: ILoggingEvent): Unit = if (e.getLevel.isGreaterOrEqual(Level.INFO)) { counted.incrementAndGet(); () }
    }
    appender.setContext(context)
    appender.setName(s"count-${System.nanoTime()}")
    appender.start()
    gateway.setLevel(Level.INFO)
    root.addAppender(appender)

    /** Lines logged since installed. */
    def count: Long = counted.get

    def close(): Unit = {
      root.detachAppender(appender)
      appender.stop()
      gateway.setLevel(levelBefore)
    }
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
