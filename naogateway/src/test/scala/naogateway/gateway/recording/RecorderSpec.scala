package naogateway.gateway.recording

import java.net.InetSocketAddress
import java.nio.file.{Files, Path}

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

import com.google.protobuf.ByteString
import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

import naogateway.proto.{
  RecordedDatagram,
  RecordedDirection,
  RecordedPort,
  RobotHealth,
  ServoState,
  ServoTelemetry,
  Status
}
import naogateway.wire.gamecontroller.GameState
import naogateway.api.recording.{Decision, RecordEncoder, Tapped}
import naogateway.gateway.tap.Tap
import naogateway.testkit.TempFiles.{withTempDir, withTempFile}

class RecorderSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {

  private val from = new InetSocketAddress("127.0.0.5", 3838)
  private val to = new InetSocketAddress("127.0.0.1", 3838)

  private def settings(dir: Path, queue: Int = 65536) =
    RecordingSettings(enabled = true, dir, rotateBytes = 64L * 1024 * 1024, rotateInterval = 10.minutes,
      queueCapacity = queue)

  private def files(dir: Path): Vector[Path] =
    Files.list(dir).iterator().asScala.filter(_.toString.endsWith(".mcap")).toVector.sortBy(_.getFileName.toString)

  "A recorder" must {
    "account for every entry handed to it, written or dropped, when its queue overflows" in {
      withTempDir("recorder-spec") { dir =>
        val tap = new Tap
        val recording = Recording(settings(dir, queue = 16), "recorder-spec-overflow", tap)
        val offered = 20000
        (1 to offered).foreach(i =>
          tap.datagram(RecordedPort.GAME_CONTROLLER, received = true, from, to, BigInt(i).toByteArray, -1))
        recording.close()
        val stats = recording.stats
        stats.dropped should be > 0L
        stats.messages + stats.dropped shouldBe offered.toLong
        val contents = McapReader.read(Files.readAllBytes(files(dir).head))
        val payloads = contents.messages.map(m => BigInt(RecordedDatagram.parseFrom(m.data).payload.toByteArray).toInt)
        payloads.size.toLong shouldBe stats.messages
        // What was written keeps its order.
        payloads shouldBe payloads.sorted
      }
    }

    "write what waits when closed, then ignore further entries" in {
      withTempDir("recorder-spec") { dir =>
        val tap = new Tap
        val recording = Recording(settings(dir), "recorder-spec-close", tap)
        tap.decision(Decision.Gate(open = false, naogateway.api.GameReading.Known(GameState.Playing)))
        recording.close()
        tap.decision(Decision.Gate(open = true, naogateway.api.GameReading.Known(GameState.Finished)))
        recording.stats.messages shouldBe 1L
        val contents = McapReader.read(Files.readAllBytes(files(dir).head))
        new String(contents.messages.head.data, "UTF-8") should include("\"decision\":\"gate-closed\"")
      }
    }

    "put a keep-alive's servo telemetry on /robot/<id>/servos, not on the message channel" in {
      withTempDir("recorder-spec") { dir =>
        val tap = new Tap
        val recording = Recording(settings(dir), "recorder-spec-servos", tap)
        val telemetry = ServoTelemetry(Vector(ServoState(1, Some(512), Some(-40), Some(121), Some(41)),
            ServoState(2, silent = Some(true))), busErrors = Some(1))
        val keepAlive = naogateway.wire.MessageContents(2, status = Some(Status(teamID = Some(1))),
          robotHealth = Some(RobotHealth(uptimeMs = Some(1000))), servoTelemetry = Some(telemetry))
        val plain = keepAlive.copy(servoTelemetry = None)
        Seq(keepAlive, plain).foreach { c =>
          tap.datagram(RecordedPort.ROBOT_PORT, received = true, from, to,
            naogateway.wire.MessageContents.encodeFrame(c).toOption.get, 2, decoded = Some(c))
        }
        recording.close()
        val contents = McapReader.read(Files.readAllBytes(files(dir).head))
        def channel(topic: String) = contents.channels.values.find(_.topic == topic).getOrElse(fail(s"no $topic"))
        def on(topic: String) = contents.messages.filter(_.channelId == channel(topic).id)
        val servos = channel(Recording.Topics.servos(2))
        servos.topic shouldBe "/robot/2/servos"
        contents.schemas(servos.schemaId).name shouldBe "naogateway.proto.ServoTelemetry"
        on("/robot/2/servos").map(m => ServoTelemetry.parseFrom(m.data)) shouldBe Vector(telemetry)
        on("/robot/2/status") should have size 2
        on("/robot/2/message") shouldBe empty
      }
    }

    "count entries it cannot write when the directory cannot be made, without failing" in {
      withTempFile("recorder-spec", ".not-a-directory") { file =>
        val tap = new Tap
        val recording = Recording(settings(file.resolve("sub")), "recorder-spec-failed", tap)
        (1 to 10).foreach(_ =>
          tap.decision(Decision.Gate(open = true, naogateway.api.GameReading.Known(GameState.Initial))))
        recording.close()
        recording.stats.failed shouldBe 10L
        recording.stats.files shouldBe 0L
      }
    }

    "begin a new file when the current one is older than rotate-interval, each file complete" in {
      withTempDir("recorder-spec") { dir =>
        val tap = new Tap
        val recording = Recording(settings(dir).copy(rotateInterval = 1.second), "recorder-spec-age", tap)
        (1 to 6).foreach { i =>
          tap.decision(Decision.Budget(i.toLong, 0L, 125000, Map.empty))
          Thread.sleep(500)
        }
        recording.close()
        val recorded = files(dir)
        recorded.size should be >= 2
        recorded.map(p => McapReader.read(Files.readAllBytes(p)).messages.size).sum shouldBe 6
      }
    }

    "encode a datagram byte for byte as the generated RecordedDatagram does, reusing its buffer" in {
      val encoder = new RecordEncoder
      val entries = for {
        port <- Gen.oneOf(RecordedPort.ROBOT_PORT, RecordedPort.GAME_CONTROLLER, RecordedPort.FU_REMOTE_RELAY)
        received <- Gen.oneOf(true, false)
        source <- Gen.oneOf("127.0.0.5:3838", "", "[::1]:65535", "\u00e9t\u00e9:1")
        destination <- Gen.oneOf("127.0.0.1:11011", "")
        size <- Gen.oneOf(0, 1, 127, 128, 2000, 70000)
        payload <- Gen.listOfN(size, Gen.choose(Byte.MinValue, Byte.MaxValue)).map(_.toArray)
        robotId <- Gen.oneOf(-1, 0, 1, 127, 128, 300, Int.MaxValue)
      } yield (Tapped.Datagram(0L, port, received, null, null, payload, robotId), source, destination)
      forAll(entries) { case (d, source, destination) =>
        val expected = RecordedDatagram(
          d.port,
          if (d.received) RecordedDirection.RECEIVED else RecordedDirection.SENT,
          source,
          destination,
          ByteString.copyFrom(d.bytes),
          if (d.robotId >= 0) Some(d.robotId) else None
        ).toByteArray
        val n = encoder.datagram(d, source.getBytes("UTF-8"), destination.getBytes("UTF-8"))
        encoder.bytes.take(n) shouldBe expected
      }
      val status = Status(timestamp = Some(123456789L), teamID = Some(3), activeAgent = Some("striker"))
      encoder.bytes.take(encoder.message(status)) shouldBe status.toByteArray
      val health = RobotHealth(uptimeMs = Some(42))
      encoder.bytes.take(encoder.message(health)) shouldBe health.toByteArray
    }

    "pause its writer longer while entries trickle in, and briefly again once they arrive in numbers" in {
      import Recorder.{MaxParkNanos, MinParkNanos, nextPark}
      val trickle = Iterator.iterate(MinParkNanos)(nextPark(_, 3)).take(20).toVector
      trickle.sliding(2).foreach { case Vector(a, b) => b should be >= a; case _ => () }
      trickle.last shouldBe MaxParkNanos
      nextPark(MaxParkNanos, 3) shouldBe MaxParkNanos // a trickle keeps the long pause
      nextPark(MaxParkNanos, 1024) shouldBe MinParkNanos // a full batch: traffic picked up
    }

    "record nothing when off" in {
      Recording(RecordingSettings.Off, "unused", new Tap) shouldBe Recording.Off
      Recording.Off.enabled shouldBe false
    }
  }
}
