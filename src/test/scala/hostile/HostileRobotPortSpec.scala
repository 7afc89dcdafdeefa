package hostile

import java.io.File
import java.net.{DatagramPacket, DatagramSocket, InetSocketAddress, SocketTimeoutException}
import java.nio.charset.StandardCharsets
import java.nio.file.Files
import java.util.concurrent.TimeUnit
import java.util.concurrent.atomic.AtomicLong

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.util.Try

import org.scalatest.BeforeAndAfterAll
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import firmware.{FirmwareBuild, Fusig2}
import naogateway.testkit.TestLoopback
import naogateway.wire.MessageContents

/** The robot's own receive port under attack from hosts on its network: the C library's posix robot, built and started
  * as docs/firmware.md shows (`make -C firmware native`, `FR_POSIX_BIND=<ip>:3838 robot id= team= player= gateway= key=
  * epoch=`), two of them on their own loopback addresses, a gateway played by this spec with a signer of its own
  * (firmware.Fusig2, the JDK's HMAC), and strangers on further 127.x addresses. The robot must answer its gateway and
  * nobody else: not a stranger, not the gateway's address at another port, not a frame naming another robot, not an
  * unsigned frame, not a frame captured for another robot, not a frame captured before its restart. Its refusal
  * counters (its output's `counters:` lines) must say why, and no stranger may hear anything from it. Loopback only;
  * every wait is bounded. Cancelled with the reason when make, a C compiler or nanopb is missing (bash
  * firmware/setup.sh installs them).
  */
class HostileRobotPortSpec extends AnyWordSpec with Matchers with BeforeAndAfterAll {
  import Fusig2._

  private val teamKey = unhex("6e616f676174657761792074657374206b6579206f662074656d6d2031322121")
  private val idA = 71
  private val idB = 72
  private val keyA = robotKey(teamKey, idA)
  private val keyB = robotKey(teamKey, idB)

  private lazy val robotBinary: File = {
    FirmwareBuild.make(this, Seq("native"))
    new File(FirmwareBuild.dir, "build/posix-w1/robot")
  }

  private val sockets = new java.util.concurrent.ConcurrentLinkedQueue[DatagramSocket]()
  private val processes = new java.util.concurrent.ConcurrentLinkedQueue[Process]()
  private lazy val work: File = Files.createTempDirectory("hostile-robot-port").toFile

  override def afterAll(): Unit = {
    processes.asScala.foreach { p => p.destroy(); if (!p.waitFor(5, TimeUnit.SECONDS)) p.destroyForcibly() }
    sockets.asScala.foreach(_.close())
    Option(work.listFiles()).foreach(_.foreach(_.delete()))
    work.delete()
    super.afterAll()
  }

  private def socket(at: InetSocketAddress): DatagramSocket = {
    val s = new DatagramSocket(at)
    sockets.add(s)
    s
  }

  /** The gateway (this spec) and the strangers: a host of its own, and the gateway's own address at another port. */
  private lazy val gateway = socket(new InetSocketAddress(TestLoopback.address(0), 0))
  private lazy val stranger = socket(new InetSocketAddress(TestLoopback.address(0), 0))
  private lazy val otherPort = socket(new InetSocketAddress(gateway.getLocalAddress, 0))
  private def gatewayAt = s"${gateway.getLocalAddress.getHostAddress}:${gateway.getLocalPort}"

  /** The gateway's timestamps: microseconds since the Unix epoch, each above the last (protocol.md 6.7). */
  private val clock = new AtomicLong(System.currentTimeMillis() * 1000L)
  private def nextTimestamp(): Long = clock.updateAndGet(t => math.max(t + 1, System.currentTimeMillis() * 1000L))
  private val callIds = new AtomicLong(5000)

  /** One posix robot process, started with the arguments docs/firmware.md gives. */
  private final class Robot(val id: Int, val key: Array[Byte], val address: InetSocketAddress, epochFile: File) {
    val log = new File(work, s"robot-$id-${System.nanoTime()}.log")
    val process: Process = {
      val b = new ProcessBuilder(Seq(robotBinary.getPath, s"id=$id", "team=12", "player=3", s"gateway=$gatewayAt",
          s"key=${hex(key)}", s"epoch=${epochFile.getPath}", "run_ms=60000").asJava)
        .redirectErrorStream(true).redirectOutput(log)
      b.environment().put("FR_POSIX_BIND", s"${address.getAddress.getHostAddress}:${address.getPort}")
      val p = b.start()
      processes.add(p)
      p
    }
    def output: String = Try(new String(Files.readAllBytes(log.toPath), StandardCharsets.UTF_8)).getOrElse("")

    /** The last `counters:` line of its output, as name -> value. */
    def counters: Map[String, Long] =
      output.linesIterator.filter(_.startsWith("counters:")).toVector.lastOption.toVector
        .flatMap(_.stripPrefix("counters:").trim.split(' ')).flatMap(_.split('=') match {
          case Array(k, v) => Some(k -> v.toLong)
          case _           => None
        }).toMap

    /** Waits (bounded) until its counters satisfy `ok`; the counters last seen. */
    def countersWhen(ok: Map[String, Long] => Boolean, within: FiniteDuration = 5.seconds): Map[String, Long] = {
      val deadline = within.fromNow
      while (!ok(counters) && deadline.hasTimeLeft()) Thread.sleep(100)
      counters
    }

    def stop(): Unit = {
      process.destroy()
      process.waitFor(5, TimeUnit.SECONDS) shouldBe true
    }
  }

  /** Datagrams that reach `on` within `within`, with their senders. */
  private def received(on: DatagramSocket, within: FiniteDuration): Vector[(Array[Byte], InetSocketAddress)] = {
    val deadline = within.fromNow
    val out = Vector.newBuilder[(Array[Byte], InetSocketAddress)]
    while (deadline.hasTimeLeft()) {
      val buf = new Array[Byte](2048)
      val p = new DatagramPacket(buf, buf.length)
      on.setSoTimeout(math.max(1, deadline.timeLeft.toMillis.toInt))
      try {
        on.receive(p)
        out += (buf.take(p.getLength) -> p.getSocketAddress.asInstanceOf[InetSocketAddress])
      } catch { case _: SocketTimeoutException => () }
    }
    out.result()
  }

  /** The first datagram from `robot` at the gateway matching `pick`, within `within`. */
  private def awaitFrom[A](robot: Robot, within: FiniteDuration)(pick: Array[Byte] => Option[A]): Option[A] = {
    val deadline = within.fromNow
    var found: Option[A] = None
    while (found.isEmpty && deadline.hasTimeLeft()) {
      val buf = new Array[Byte](2048)
      val p = new DatagramPacket(buf, buf.length)
      gateway.setSoTimeout(math.max(1, deadline.timeLeft.toMillis.toInt))
      try {
        gateway.receive(p)
        if (p.getSocketAddress == robot.address) found = pick(buf.take(p.getLength))
      } catch { case _: SocketTimeoutException => () }
    }
    found
  }

  /** The robot's boot epoch from its signed keep-alives, which must verify under its robot key. */
  private def epochOf(robot: Robot): Int =
    withClue(s"no keep-alive of robot ${robot.id} verified; its output:\n${robot.output}\n") {
      awaitFrom(robot, 5.seconds)(frame => verifyRobotFrame(robot.key, robot.id, frame).map(_._1)).get
    }

  /** Whether `robot` answers call `callId` at the gateway within `within`, with a signature that verifies. */
  private def answered(robot: Robot, callId: Int, within: FiniteDuration = 2.seconds): Boolean =
    awaitFrom(robot, within) { frame =>
      MessageContents.decodeFrame(frame).toOption.collect {
        case (_, c) if c.rpcResponse.exists(_.callId.contains(callId)) =>
          verifyRobotFrame(robot.key, robot.id, frame).isDefined
      }
    }.contains(true)

  private def send(from: DatagramSocket, to: Robot, frame: Array[Byte]): Unit =
    from.send(new DatagramPacket(frame, frame.length, to.address))

  /** A signed system.ping for `robot` in `epoch`, with a fresh call id and timestamp. */
  private def signedPing(robot: Robot, epoch: Int): (Int, Array[Byte]) = {
    val callId = callIds.incrementAndGet().toInt
    callId -> signedFrame(robot.key, robot.id, epoch, nextTimestamp(), request(robot.id, "system", "ping", callId))
  }

  private lazy val epochFileA = new File(work, "robot-a.epoch")
  private lazy val robotA = new Robot(idA, keyA, TestLoopback.robotAt(), epochFileA)
  private lazy val robotB = new Robot(idB, keyB, TestLoopback.robotAt(), new File(work, "robot-b.epoch"))
  private lazy val epochA = epochOf(robotA)
  private lazy val epochB = epochOf(robotB)

  /** Frames the gateway sent robot A that A answered: captured for the replays below. */
  private var capturedForA: Array[Byte] = Array.emptyByteArray

  "The posix robot's receive port" should {
    "answer its gateway's signed request, the test-side signer agreeing with the robot's in both directions" in {
      robotA.process.isAlive shouldBe true
      val (callId, frame) = signedPing(robotA, epochA)
      send(gateway, robotA, frame)
      withClue(s"robot output:\n${robotA.output}\n") { answered(robotA, callId) shouldBe true }
      capturedForA = frame
      epochB should be >= 1
    }

    "answer no stranger, nor the gateway's own address at another port, even with a valid signature" in {
      val before = robotA.counters.getOrElse("stranger", 0L)
      val (fromStranger, f1) = signedPing(robotA, epochA)
      send(stranger, robotA, f1)
      val (fromOtherPort, f2) = signedPing(robotA, epochA)
      send(otherPort, robotA, f2)
      received(stranger, 1.second) shouldBe empty
      received(otherPort, 200.millis) shouldBe empty
      answered(robotA, fromStranger, 300.millis) shouldBe false
      answered(robotA, fromOtherPort, 300.millis) shouldBe false
      robotA.countersWhen(_.getOrElse("stranger", 0L) >= before + 2)("stranger") shouldBe before + 2
    }

    "refuse a request naming another robot's id, and an unsigned request" in {
      val callId = callIds.incrementAndGet().toInt
      send(gateway, robotA, signedFrame(keyB, idB, epochA, nextTimestamp(), request(idB, "system", "ping", callId)))
      val unsignedCall = callIds.incrementAndGet().toInt
      send(gateway, robotA, frame(request(idA, "system", "ping", unsignedCall)))
      answered(robotA, callId, 1.second) shouldBe false
      answered(robotA, unsignedCall, 300.millis) shouldBe false
      val c = robotA.countersWhen(c => c.getOrElse("wrong_robot", 0L) >= 1 && c.getOrElse("unsigned", 0L) >= 1)
      c("wrong_robot") shouldBe 1
      c("unsigned") shouldBe 1
    }

    "refuse a frame captured for robot A when it is replayed to robot B, as it is or renamed to B" in {
      capturedForA should not be empty
      send(gateway, robotB, capturedForA)
      // The same frame with its robotID byte changed to B's: the MAC was made for A (its key, its id).
      val renamed = capturedForA.clone()
      renamed(13) shouldBe idA.toByte
      renamed(13) = idB.toByte
      send(gateway, robotB, renamed)
      received(stranger, 500.millis) shouldBe empty
      val c = robotB.countersWhen(c => c.getOrElse("wrong_robot", 0L) >= 1 && c.getOrElse("bad_signature", 0L) >= 1)
      c("wrong_robot") shouldBe 1
      c("bad_signature") shouldBe 1
      // B still answers its own gateway.
      val (callId, frame) = signedPing(robotB, epochB)
      send(gateway, robotB, frame)
      withClue(s"robot B output:\n${robotB.output}\n") { answered(robotB, callId) shouldBe true }
    }

    "refuse a frame captured before the robot's restart: the same epoch file gives it the next epoch" in {
      // Signed for A's current epoch with the newest timestamp of all, but delivered only after the restart.
      val (held, heldFrame) = signedPing(robotA, epochA)
      robotA.stop()
      val restarted = new Robot(idA, keyA, robotA.address, epochFileA)
      val newEpoch = epochOf(restarted)
      newEpoch shouldBe epochA + 1
      new String(Files.readAllBytes(epochFileA.toPath), StandardCharsets.US_ASCII).trim shouldBe newEpoch.toString
      send(gateway, restarted, heldFrame)
      send(gateway, restarted, capturedForA)
      answered(restarted, held, 1.second) shouldBe false
      restarted.countersWhen(_.getOrElse("bad_signature", 0L) >= 2)("bad_signature") shouldBe 2
      // Signed for the new epoch, the gateway's requests are answered again.
      val (callId, frame) = signedPing(restarted, newEpoch)
      send(gateway, restarted, frame)
      withClue(s"robot output:\n${restarted.output}\n") { answered(restarted, callId) shouldBe true }
      // Nothing the robots sent ever reached a stranger.
      received(stranger, 300.millis) shouldBe empty
      received(otherPort, 100.millis) shouldBe empty
    }

    "not start at all with no key, or a key that is short, long, of odd length or not hex: a message, never the key" in {
      val address = TestLoopback.robotAt()
      val cases = Seq(
        Seq.empty[String] -> "no signing key",
        Seq("key=" + "ab" * 15) -> "too short",
        Seq("key=" + "ab" * 65) -> "too long",
        Seq("key=" + "ab" * 16 + "c") -> "odd number",
        Seq("key=" + "ab" * 15 + "zz") -> "not a hex digit",
        Seq("key=" + "ab" * 16, "development") -> "development build takes no signing key"
      )
      cases.foreach { case (args, reason) =>
        val log = new File(work, s"refused-${System.nanoTime()}.log")
        val b = new ProcessBuilder((Seq(robotBinary.getPath, "id=75", "team=12", "player=3", s"gateway=$gatewayAt",
            s"epoch=${new File(work, "robot-75.epoch").getPath}") ++ args).asJava)
          .redirectErrorStream(true).redirectOutput(log)
        b.environment().put("FR_POSIX_BIND", s"${address.getAddress.getHostAddress}:${address.getPort}")
        val p = b.start()
        processes.add(p)
        withClue(s"arguments ${args.map(_.take(12))}: ") {
          p.waitFor(5, TimeUnit.SECONDS) shouldBe true
          p.exitValue() shouldBe 2
          val out = new String(Files.readAllBytes(log.toPath), StandardCharsets.UTF_8)
          out should include("cannot start")
          out should include(reason)
          args.filter(_.startsWith("key=")).foreach(k => out should not include k.stripPrefix("key=").take(20))
        }
      }
      // None of them sent anything, and none took an epoch.
      received(gateway, 300.millis).map(_._2).filter(_ == address) shouldBe empty
      new File(work, "robot-75.epoch").exists() shouldBe false
    }
  }
}
