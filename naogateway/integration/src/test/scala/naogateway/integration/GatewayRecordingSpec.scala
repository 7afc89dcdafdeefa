package naogateway.integration

import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel
import java.nio.charset.StandardCharsets
import java.nio.file.{Files, Path}

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.RobotAccess
import naogateway.api.{CallResult, RobotOffline, RobotOnline, RobotStatusUpdated}
import naogateway.proto.{RecordedDatagram, RecordedDirection, RecordedPort, Status}
import naogateway.testkit.TestLoopback
import naogateway.testkit.TempFiles.withTempDir
import naogateway.wire.RpcCall
import naogateway.gateway.recording.{Mcap, McapReader, Recording}

/** A gateway with recording on, a simulated robot and a few datagrams of the test's own, then the file it left. */
class GatewayRecordingSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  /** The messages of each topic in the first recording file of `dir`, none for a topic it has no channel of. */
  private def recorded(dir: Path): String => Vector[Mcap.Message] = {
    val contents = McapReader.read(Files.readAllBytes(files(dir).head))
    topic =>
      contents.channels.values.find(_.topic == topic).toVector.flatMap(c =>
        contents.messages.filter(_.channelId == c.id))
  }

  /** The recording's files in the order they were begun: by their counter `-<n>.mcap` (as a number: -10 after -9). */
  private def files(dir: Path): Vector[Path] = {
    val counter = """-(\d+)\.mcap$""".r.unanchored
    Files.list(dir).iterator().asScala.filter(_.toString.endsWith(".mcap")).toVector.sortBy { p =>
      val name = p.getFileName.toString
      name match {
        case counter(n) => (name.substring(0, name.lastIndexOf('-')), n.toInt)
        case _          => (name, 0)
      }
    }
  }

  "A recording gateway" must {
    "write every datagram byte for byte, the robot's Status decoded, and its decisions, into an MCAP file closed on stop" in {
      withTempDir("recording-spec") { dir =>
        val relayTarget = DatagramChannel.open().bind(new InetSocketAddress(TestLoopback.address(0), 0))
        val relayAt = relayTarget.getLocalAddress.asInstanceOf[InetSocketAddress]
        val f = new GatewayFixture(
          testKit,
          s"""recording { enabled = on, directory = "${dir.toString}" }
             |fu-remote-relay { enabled = on, address = "${relayAt.getAddress.getHostAddress}", port = ${relayAt
              .getPort} }
             |""".stripMargin
        )
        val stranger = DatagramChannel.open().bind(new InetSocketAddress(TestLoopback.address(0), 0))
        val strangerAt = stranger.getLocalAddress.asInstanceOf[InetSocketAddress]
        val odd = "not a frame at all \u0000\u00ff".getBytes(StandardCharsets.ISO_8859_1)
        try {
          f.robot(7)
          f.awaitEvent(10.seconds) { case RobotOnline(7, _) => () }
          // Until the robot's clock is estimated, and one more keep-alive after it (dated by that estimate).
          f.awaitEvent(20.seconds) {
            case RobotStatusUpdated(snapshot) if snapshot.robotId == 7 && snapshot.clock.isDefined => ()
          }
          f.awaitEvent(5.seconds) { case RobotStatusUpdated(snapshot) if snapshot.robotId == 7 => () }
          stranger.send(ByteBuffer.wrap(odd), f.addresses.robots)
          val probe = createTestProbe[CallResult]()
          f.connect(7).response ! RobotAccess.Call(RpcCall("system", "ping", Vector.empty), probe.ref)
          probe.receiveMessage(10.seconds).result.isRight shouldBe true
          // Until the stranger's datagram has passed the reader (its refusal is counted).
          createTestProbe[Any]().awaitAssert(f.stats().rejected.values.sum should be >= 1L, 5.seconds)
          f.stats().recording.enabled shouldBe true
        } finally {
          f.stop()
          stranger.close()
          relayTarget.close()
        }

        val recorded = files(dir)
        recorded should have size 1
        val contents = McapReader.read(Files.readAllBytes(recorded.head))
        def channel(topic: String): Mcap.Channel =
          contents.channels.values.find(_.topic == topic).getOrElse(fail(s"no channel $topic"))
        def on(topic: String): Vector[Mcap.Message] = contents.messages.filter(_.channelId == channel(topic).id)

        val datagrams = on(Recording.Topics.Datagrams).map(m => RecordedDatagram.parseFrom(m.data))
        contents.schemas(channel(Recording.Topics.Datagrams).schemaId).name shouldBe "naogateway.proto.RecordedDatagram"
        val fromStranger =
          datagrams.filter(_.source == s"${strangerAt.getAddress.getHostAddress}:${strangerAt.getPort}")
        fromStranger.map(_.payload.toByteArray.toVector) shouldBe Vector(odd.toVector)
        fromStranger.head.port shouldBe RecordedPort.ROBOT_PORT
        fromStranger.head.direction shouldBe RecordedDirection.RECEIVED
        // Relayed to FU-Remote, the same bytes.
        datagrams.filter(d => d.port == RecordedPort.FU_REMOTE_RELAY).map(
          _.payload.toByteArray.toVector) should contain(
          odd.toVector)
        // The robot's keep-alives, and what the gateway sent it (the debug option pull, the ping).
        datagrams.count(d => d.robotID.contains(7) && d.direction == RecordedDirection.RECEIVED) should be > 1
        datagrams.count(d =>
          d.robotID.contains(7) && d.direction == RecordedDirection.SENT && d.port == RecordedPort.ROBOT_PORT) should be >= 1

        val statusMessages = on(Recording.Topics.status(7))
        val statuses = statusMessages.map(m => Status.parseFrom(m.data))
        // Once the robot's clock is estimated, a Status is published at its own time put on the gateway's clock: on
        // loopback, shortly before the gateway received it.
        val dated = statusMessages.filter(m => m.publishTime != m.logTime)
        dated should not be empty
        dated.foreach(m => math.abs(m.logTime - m.publishTime) should be < 1000000000L)
        statuses should not be empty
        statuses.flatMap(_.teamID).distinct shouldBe Vector(1)
        contents.schemas(channel(Recording.Topics.status(7)).schemaId).name shouldBe "naogateway.proto.Status"

        val decisions: Vector[String] =
          on(Recording.Topics.Decisions).map(m => new String(m.data, StandardCharsets.UTF_8))
        channel(Recording.Topics.Decisions).messageEncoding shouldBe "json"
        decisions.exists(d => d.contains("\"decision\":\"robot-online\"") && d.contains("\"robotId\":7")) shouldBe true
        decisions.exists(d =>
          d.contains("\"decision\":\"send\"") && d.contains("\"call\":\"system.ping\"") &&
            d.contains("\"outcome\":\"sent\"")) shouldBe true
        withClue(decisions.mkString("\n")) {
          decisions.exists(d => d.contains("\"decision\":\"reply\"") && d.contains("\"outcome\":\"ok\"")) shouldBe true
        }
        decisions.exists(_.contains("\"decision\":\"budget\"")) shouldBe true
        contents.statistics.map(_.messageCount) shouldBe Some(contents.messages.size.toLong)
      }
    }

    "keep a stranger's frame in another robot's name raw: never on that robot's decoded channels" in {
      withTempDir("recording-spec-stranger") { dir =>
        val f = new GatewayFixture(testKit, s"""recording { enabled = on, directory = "${dir.toString}" }""")
        // From another loopback address, in robot 7's name: a Status of another team, and a reply to no call.
        val stranger = DatagramChannel.open().bind(new InetSocketAddress(TestLoopback.address(0), 0))
        val strangerAt = s"${stranger.socket().getLocalAddress.getHostAddress}:"
        val forged = naogateway.wire.MessageContents.encodeFrame(naogateway.wire.MessageContents(7,
            status = Some(Status(teamID = Some(99))))).toOption.get
        try {
          f.robot(7)
          f.awaitEvent(10.seconds) { case RobotOnline(7, _) => () }
          val before = f.stats().rejected.values.sum
          (1 to 5).foreach(_ => stranger.send(ByteBuffer.wrap(forged), f.addresses.robots))
          createTestProbe[Any]().awaitAssert(f.stats().rejected.values.sum should be >= before + 5, 5.seconds)
          f.awaitEvent(5.seconds) { case RobotStatusUpdated(snapshot) if snapshot.robotId == 7 => () }
        } finally {
          f.stop()
          stranger.close()
        }
        val on = recorded(dir)
        // Kept byte for byte as what crossed the port ...
        on(Recording.Topics.Datagrams).map(m => RecordedDatagram.parseFrom(m.data))
          .count(_.source.startsWith(strangerAt)) shouldBe 5
        // ... but robot 7's channels hold its own keep-alives only.
        on(Recording.Topics.status(7)).map(m => Status.parseFrom(m.data)).flatMap(_.teamID).distinct shouldBe Vector(1)
      }
    }

    "let a stranger's burst wake its gathering writer and change nothing else: the robot, its channels, no entry lost" in {
      // The writer pauses up to 250 ms after a trickle; a quarter of its queue waiting wakes it early (the tap's offer,
      // on the port's read path, decides). What may a stranger on the field do with that? Random bytes, frames in
      // another robot's name and a replay of this robot's own keep-alive, from another loopback address, about 8,000 a
      // second into a queue of 512. (That the count wakes the writer is TapSpec's; this says what the stranger gets.)
      withTempDir("recording-spec-burst") { dir =>
        // As on a field: the team's robot listed, nothing discovered.
        val ip = TestLoopback.address()
        val f = new GatewayFixture(
          testKit,
          s"""recording { enabled = on, directory = "${dir.toString}", queue-capacity = 512 }
             |robots = [{ id = 7, address = "${ip.getHostAddress}" }]
             |discovery.enabled = off""".stripMargin
        )
        val stranger = DatagramChannel.open().bind(new InetSocketAddress(TestLoopback.address(0), 0))
        val strangerAt = s"${stranger.socket().getLocalAddress.getHostAddress}:"
        def frame(robotId: Int, team: Int) = naogateway.wire.MessageContents.encodeFrame(
          naogateway.wire.MessageContents(robotId, status = Some(Status(teamID = Some(team))))).toOption.get
        val random = new scala.util.Random(32)
        val kinds: Vector[() => Array[Byte]] = Vector(
          () => { val b = new Array[Byte](1 + random.nextInt(200)); random.nextBytes(b); b },
          () => frame(8, 1), // another robot's id
          () => frame(7, 99), // in this robot's name, another team
          () => frame(7, 1) // a replay: what robot 7's keep-alive carries
        )
        val burst = 1600
        try {
          f.robot(7, at = ip)
          f.awaitEvent(10.seconds) { case RobotOnline(7, _) => () }
          // A trickle of keep-alives: the writer's pause grows to its longest.
          (1 to 10).foreach(_ => f.awaitEvent(5.seconds) { case RobotStatusUpdated(s) if s.robotId == 7 => () })
          val before = f.stats()
          (0 until burst).foreach { i =>
            stranger.send(ByteBuffer.wrap(kinds(i % kinds.size)()), f.addresses.robots)
            if (i % 40 == 39) Thread.sleep(5) // about 8,000 a second: 512 entries in 64 ms
          }
          createTestProbe[Any]().awaitAssert(f.stats().datagramsIn should be >= before.datagramsIn + burst, 10.seconds)
          // The robot goes on as before: online, its own team, no other robot made, nothing it sent lost.
          (1 to 5).foreach { _ =>
            f.awaitEvent(5.seconds) {
              case e: RobotOffline                         => fail(s"the burst changed the robots: $e")
              case e @ RobotOnline(id, _) if id != 7       => fail(s"the burst made a robot: $e")
              case RobotStatusUpdated(s) if s.robotId == 7 => s.teamId shouldBe Some(1)
            }
          }
          f.stats().robots shouldBe 1
          f.stats().recording.dropped shouldBe 0L
        } finally {
          f.stop()
          stranger.close()
        }
        val on = recorded(dir)
        // Every datagram of the burst is in the recording, raw; robot 7's channel holds its own team only, and no
        // channel of robot 8 was made.
        on(Recording.Topics.Datagrams).map(m => RecordedDatagram.parseFrom(m.data))
          .count(_.source.startsWith(strangerAt)) shouldBe burst
        on(Recording.Topics.status(7)).map(m => Status.parseFrom(m.data)).flatMap(_.teamID).distinct shouldBe Vector(1)
        on(Recording.Topics.status(8)) shouldBe empty
      }
    }

    "rotate its files by size and close each properly" in {
      withTempDir("recording-rotate-spec") { dir =>
        val f = new GatewayFixture(testKit,
          s"""recording { enabled = on, directory = "${dir.toString}", rotate-bytes = 64KiB }""")
        val sender = DatagramChannel.open().bind(new InetSocketAddress(TestLoopback.address(0), 0))
        try {
          val payload = new Array[Byte](1000)
          (1 to 300).foreach { i =>
            payload(0) = i.toByte
            sender.send(ByteBuffer.wrap(payload), f.addresses.robots)
            if (i % 50 == 0) Thread.sleep(20)
          }
          createTestProbe[Any]().awaitAssert(f.stats().datagramsIn shouldBe 300L, 10.seconds)
        } finally {
          f.stop()
          sender.close()
        }
        val recorded = files(dir)
        recorded.size should be >= 3
        val all = recorded.flatMap { p =>
          val c = McapReader.read(Files.readAllBytes(p))
          val id = c.channels.values.find(_.topic == Recording.Topics.Datagrams).get.id
          c.messages.filter(_.channelId == id).map(m => RecordedDatagram.parseFrom(m.data))
        }
        all.map(_.payload.byteAt(0) & 0xff) shouldBe (1 to 300).map(_ & 0xff).toVector
      }
    }
  }
}
