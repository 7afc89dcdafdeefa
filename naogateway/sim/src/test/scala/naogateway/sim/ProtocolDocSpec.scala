package naogateway.sim

import java.nio.charset.StandardCharsets.{US_ASCII, UTF_8}
import java.nio.file.{Files, Path, Paths}

import scala.collection.immutable.ListMap
import scala.collection.mutable
import scala.jdk.CollectionConverters._

import com.google.protobuf.ByteString
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.proto._
import naogateway.sim.{Destination, FirmwareSettings, FirmwareState, Outgoing, RobotFirmware}
import naogateway.wire.gamecontroller.{
  GameControlVersion,
  GameControllerCodec,
  GameState,
  Hsl20Penalty,
  PlayerPenalty,
  ReturnStatus
}
import naogateway.wire.{
  FrameHeader,
  FrameSigning,
  FumanoidsFrame,
  HaViMo,
  HaViMoRegion,
  HeaderForm,
  MessageContents,
  ReplayWindow,
  SignDirection,
  SignatureError,
  SignedBody,
  SignedLink,
  SigningKey,
  WireLimits
}

/** Keeps docs/protocol.md true. Every `<!-- example: tag -->` / `<!-- datagrams: tag -->` hex block and every `<!--
  * table: tag -->` offset table in the document is checked here: FU-Remote frames against the codecs (decode to the
  * expected contents, re-encode to the identical bytes), GameController bytes and tables against the real packets in
  * the test resources' vectors/gamecontroller, secure-stream datagrams against a reference model of the stream rules.
  * The keep-alive example and the debug option catalogue are checked against the simulated firmware as well.
  */
class ProtocolDocSpec extends AnyWordSpec with Matchers {
  import ProtocolDocSpec._

  private lazy val doc: ProtocolDoc = ProtocolDoc.load().fold(problem => fail(problem), identity)

  private def bytes(tag: String): Array[Byte] = doc.block(tag).fold(problem => fail(problem), _.bytes)
  private def lines(tag: String): Vector[Array[Byte]] = doc.block(tag).fold(problem => fail(problem), _.lines)
  private def table(tag: String): Table = doc.table(tag).fold(problem => fail(problem), identity)

  private def contents(tag: String): MessageContents = {
    val decoded = MessageContents.decodeFrame(bytes(tag))
    withClue(s"example $tag: ") { decoded.isRight shouldBe true }
    decoded.toOption.get._2
  }

  "docs/protocol.md" should {
    "hold exactly the tagged examples and tables this spec checks, each once" in {
      doc.blocks.map(_.tag).diff(doc.blocks.map(_.tag).distinct) shouldBe empty
      doc.tables.map(_.tag).diff(doc.tables.map(_.tag).distinct) shouldBe empty
      doc.blocks.filter(_.kind == "example").map(_.tag).toSet shouldBe ExampleTags
      doc.blocks.filter(_.kind == "datagrams").map(_.tag).toSet shouldBe DatagramTags
      doc.tables.map(_.tag).toSet shouldBe TableTags
    }
    "keep every datagram within the 1400-byte limit" in {
      for (block <- doc.blocks; datagram <- if (block.kind == "datagrams") block.lines else Vector(block.bytes))
        if (!block.tag.startsWith("serial-"))
          withClue(block.tag) { datagram.length should be <= WireLimits.MaxDatagramBytes }
    }
  }

  "The byte tables below the examples" should {
    "exist for every example but the bare pure ACK, the stream RPC segment and the RGrt packet" in {
      doc.blocks.filter(b => b.annotation.exists(isByteTable)).map(_.tag).toSet shouldBe
        (ExampleTags ++ DatagramTags -- Set("stream-pure-ack", "stream-data-rpc", "gc-return-alive",
          "gc-status-example"))
    }
    "give every byte of each example at its offset, in order, without gaps" in {
      for (block <- doc.blocks; table <- block.annotation if isByteTable(table)) withClue(s"${block.tag}: ") {
        val header = table.head
        val bytesColumn = header.indexOf("bytes")
        if (block.kind == "datagrams") {
          table.tail.map(row => parseHex(row(bytesColumn)).map(_.toVector)) shouldBe
            block.lines.map(line => Right(line.toVector))
        } else {
          val datagram = block.bytes
          val end = table.tail.zipWithIndex.foldLeft(0) { case (offset, (row, i)) =>
            withClue(s"row ${row.mkString(" | ")}: ") {
              row(0).toInt shouldBe offset
              val cell = row(bytesColumn)
              val abbreviated = cell.endsWith("\u2026")
              val shown = parseHex(cell.stripSuffix("\u2026").trim)
              shown.isRight shouldBe true
              val quoted = shown.toOption.get
              datagram.slice(offset, offset + quoted.length).toVector shouldBe quoted.toVector
              if (abbreviated) { i shouldBe table.length - 2; datagram.length }
              else offset + quoted.length
            }
          }
          end shouldBe datagram.length
        }
      }
    }
  }

  "Every FU-Remote frame example" should {
    FrameExamples.foreach { case (tag, expected) =>
      s"decode to its contents and re-encode to the identical bytes: $tag" in {
        val framed = bytes(tag)
        MessageContents.decodeFrame(framed) shouldBe Right(
          FrameHeader(expected.form, expected.gzip, framed.length - expected.form.headerBytes) -> expected.contents
        )
        MessageContents.encodeFrame(expected.contents, expected.form, expected.gzip).map(_.toVector) shouldBe
          Right(framed.toVector)
        classify(framed) shouldBe FuRemote
      }
    }
  }

  "The frame examples" should {
    "show the same protobuf bytes in the legacy, compact and gzip forms" in {
      val protobuf = bytes("status-legacy").drop(HeaderForm.Legacy.headerBytes).toVector
      bytes("status-compact").drop(HeaderForm.Compact.headerBytes).toVector shouldBe protobuf
      FumanoidsFrame.decodeRaw(bytes("status-gzip")).map(_.protobuf.toVector) shouldBe Right(protobuf)
    }
    "pair each RPC response with its request's callId" in {
      val walk = contents("rpc-request-walk").rpcRequest.get
      contents("rpc-response-walk").rpcResponse.get.callId shouldBe walk.callId
      val probe = contents("rpc-request-probe").rpcRequest.get
      val error = contents("rpc-response-unknown").rpcResponse.get
      error.callId shouldBe probe.callId
      error.error shouldBe Some(s"unknown method: ${probe.module}.${probe.method}")
    }
    "show the keep-alive exactly as the simulated firmware sends it 5000 ms after power-up" in {
      val (state, sent) = keepAliveAt5000
      val keepAlives = sent.filter(_.to == Destination.Gateway).map(_.bytes)
        .filter(b => MessageContents.decodeFrame(b).exists(_._2.status.isDefined))
      keepAlives.map(_.toVector) shouldBe Vector(bytes("keep-alive").toVector)
      MessageContents.encodeFrame(RobotFirmware.keepAlive(state)).map(_.toVector) shouldBe Right(
        bytes("keep-alive").toVector)
    }
    "carry a region whose centre is (80, 60)" in {
      val records = contents("havimo-regions").havimoRegions.get.records.get.toByteArray
      val regions = HaViMo.decodeRegions(records).toOption.get
      regions should have size 1
      val region = regions.head
      (region.centreX, region.centreY) shouldBe ((80.0, 60.0))
    }
  }

  "The robot key vector of 6.7" should {
    "be robot 1's key derived from the documented team key, computed here with the JDK's HMAC as firmware would" in {
      val team = Array.tabulate[Byte](32)(_.toByte)
      SigningKey.fromBytes(team).toOption.get.robotKey(1).toHex shouldBe
        bytes("robot-key-1").map(b => f"${b & 0xff}%02x").mkString
      def hmac(key: Array[Byte], data: Array[Byte]*): Array[Byte] = {
        val mac = javax.crypto.Mac.getInstance("HmacSHA256")
        mac.init(new javax.crypto.spec.SecretKeySpec(key, "HmacSHA256"))
        data.foreach(d => mac.update(d))
        mac.doFinal()
      }
      // RFC 5869 by hand: extract with the salt, then one expand block (L = 32).
      val prk = hmac("naogateway robot key".getBytes(US_ASCII), team)
      val info = "FUSIG2".getBytes(US_ASCII) ++ Array[Byte](0, 0, 0, 1)
      hmac(prk, info, Array[Byte](1)).toVector shouldBe bytes("robot-key-1").toVector
      prk.map(b => f"${b & 0xff}%02X").mkString(" ") shouldBe
        "2D 19 E5 7F C5 DD 4C 97 AC C2 E1 45 F9 92 AE 62 FF 10 0D 7D 6D 51 DE B1 8B CB A9 80 23 24 A5 F6"
    }
  }

  "The signed frame example of 9.14" should {
    val team = SigningKey.fromHex("000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f").toOption.get
    val key = team.robotKey(1)
    val link = SignedLink.FromRobot(1)
    val timestamp = FrameSigning.robotTimestamp(bootEpoch = 3, frameCounter = 5)
    "be the Status of 9.2 signed by robot 1 under its documented key and timestamp" in {
      timestamp shouldBe 0x0000000300000005L
      FrameSigning.signFrame(workedStatus, HeaderForm.Compact, key, link, timestamp).map(_.toVector) shouldBe
        Right(bytes("signed-status").toVector)
      val header = FumanoidsFrame.decodeHeader(bytes("signed-status")).toOption.get
      FrameSigning.verifyFrame(bytes("signed-status"), header, key, link) shouldBe
        Right(SignedBody(timestamp, bytes("status-compact").length - HeaderForm.Compact.headerBytes))
      // A peer that does not sign reads 9.2 with one unknown extension.
      MessageContents.decodeFrame(bytes("signed-status")).map(_._2) shouldBe
        Right(workedStatus.copy(unknownExtensions = Vector(FrameSigning.Field)))
    }
    "show the HMAC input, whose HMAC-SHA256 under robot 1's key begins with the frame's mac" in {
      val input = bytes("signed-status-mac-input")
      input.toVector shouldBe (FrameSigning.Domain ++ Array[Byte](SignDirection.RobotToGateway.code) ++
        java.nio.ByteBuffer.allocate(16).putInt(1).putInt(3).putLong(timestamp).array() ++
        bytes("status-compact").drop(HeaderForm.Compact.headerBytes)).toVector
      FrameSigning.macPrefix(link, timestamp).toVector shouldBe input.take(23).toVector
      // Computed here without the codec, as firmware would.
      val hmac = javax.crypto.Mac.getInstance("HmacSHA256")
      hmac.init(new javax.crypto.spec.SecretKeySpec(bytes("robot-key-1"), "HmacSHA256"))
      hmac.doFinal(input).take(FrameSigning.MacBytes).toVector shouldBe bytes("signed-status").takeRight(
        FrameSigning.MacBytes).toVector
    }
    "show the gateway's optionPull of 9.8 to robot 1 in epoch 3, good in that epoch only" in {
      val toRobot = SignedLink.ToRobot(1, 3)
      val gatewayTimestamp = 1764000000000000L
      val frame = bytes("signed-option-pull")
      FrameSigning.signEncoded(bytes("debug-option-pull"), key, toRobot, gatewayTimestamp).map(_.toVector) shouldBe
        Right(frame.toVector)
      val header = FumanoidsFrame.decodeHeader(frame).toOption.get
      FrameSigning.verifyFrame(frame, header, key, toRobot).map(_.timestamp) shouldBe Right(gatewayTimestamp)
      FrameSigning.verifyFrame(frame, header, key, SignedLink.ToRobot(1, 4)) shouldBe Left(SignatureError.BadMac)
      FrameSigning.macPrefix(toRobot, gatewayTimestamp).map(b => f"${b & 0xff}%02X").mkString(" ") shouldBe
        "46 55 53 49 47 32 02 00 00 00 01 00 00 00 03 00 06 44 59 41 62 40 00"
    }
    "be refused as a copy, as robot 2's, and as the gateway's; a later epoch is above it" in {
      ReplayWindow.empty.accept(timestamp).flatMap(_.accept(timestamp)) shouldBe Left(SignatureError.Replayed)
      ReplayWindow(Some(timestamp)).accept(FrameSigning.robotTimestamp(4, 0)).isRight shouldBe true
      val header = FumanoidsFrame.decodeHeader(bytes("signed-status")).toOption.get
      FrameSigning.verifyFrame(bytes("signed-status"), header, key, SignedLink.ToRobot(1, 3)) shouldBe Left(
        SignatureError.BadMac)
      val asRobot2 = bytes("signed-status").clone()
      asRobot2(9) = 2
      FrameSigning.verifyFrame(asRobot2, header, team.robotKey(2), SignedLink.FromRobot(2)) shouldBe Left(
        SignatureError.BadMac)
    }
  }

  "The extension tables" should {
    val extensions = Seq(MessageProto, DebuggingProto, HavimoProto, RpcProto, BodyProto)
      .flatMap(_.javaDescriptor.getExtensions.asScala)
      .map(f => (f.getNumber, f.getName, f.getMessageType.getName, Paths.get(f.getFile.getName).getFileName.toString))
    "list exactly the extensions of the .proto files, with their numbers, messages and files" in {
      table("extension-numbers").rows.map(r => (r(0).toInt, r(1), r(2), r(3))).toSet shouldBe extensions.toSet
    }
    "keep this project's numbers in 7100-7199 and agree with MessageContents" in {
      val byName = extensions.map(e => e._2 -> e._1).toMap
      byName("status") shouldBe MessageContents.StatusField
      byName("debuggingCommands") shouldBe MessageContents.DebuggingCommandsField
      byName("debugData") shouldBe MessageContents.DebugDataField
      byName("havimoRegions") shouldBe MessageContents.HavimoRegionsField
      byName("havimoGrid") shouldBe MessageContents.HavimoGridField
      byName("robotHealth") shouldBe MessageContents.RobotHealthField
      byName("rpcRequest") shouldBe MessageContents.RpcRequestField
      byName("rpcResponse") shouldBe MessageContents.RpcResponseField
      byName("servoTelemetry") shouldBe MessageContents.ServoTelemetryField
      all((byName - "status").values) should (be >= MessageContents.ProjectRange.start and
        be <= MessageContents.ProjectRange.end)
    }
    "give each extension's key bytes correctly" in {
      val rows = table("extension-keys").rows
      rows.map(_(0)).toSet shouldBe extensions.map(_._2).toSet
      rows.foreach { r =>
        withClue(r(0)) {
          r(1).toInt shouldBe extensions.find(_._2 == r(0)).get._1
          parseHex(r(2)).map(_.toVector) shouldBe Right(varint((r(1).toLong << 3) | 2).toVector)
        }
      }
    }
  }

  "The debug option catalogue of section 8" should {
    "list exactly the simulated firmware's options, in its order, with their types" in {
      table("debug-options").rows.map(r => (r(0), r(1))) shouldBe
        RobotFirmware.OptionCatalogue.map { case (name, kind, _) => (name, s"${kind.name} (${kind.value})") }
    }
  }

  "The GameController examples and tables" should {
    lazy val v8 = vector("v8-playing.bin")
    lazy val v7 = vector("v7-playing.bin")

    "quote the first bytes of the real packets" in {
      bytes("gc-v8-header").toVector shouldBe v8.take(18).toVector
      bytes("gc-v7-header").toVector shouldBe v7.take(20).toVector
      classify(v8) shouldBe GameController
    }
    "give version 8 offsets that add up to 158 bytes and read the real packet right" in {
      val packet = table("gc-v8")
      val team = table("gc-v8-team")
      v8.length shouldBe 158
      contiguous(packet, offsetColumn = 0, sizeColumn = 1) shouldBe 158
      contiguous(team, offsetColumn = 0, sizeColumn = 3) shouldBe 70
      teamOffsetsAgree(packet, team, fieldColumn = 2)
      val read = reader(v8, packet, offsetColumn = 0, sizeColumn = 1, typeColumn = 3, fieldColumn = 2)
      new String(v8.slice(0, 4), US_ASCII) shouldBe "RGme"
      read("version") shouldBe 8
      read("packetNumber") shouldBe 4
      read("playersPerTeam") shouldBe 6
      read("gameState") shouldBe 3
      read("firstHalf") shouldBe 1
      read("kickOffTeam") shouldBe 1
      read("secGameState") shouldBe 0
      read("dropInTime") shouldBe -1
      read("secsRemaining") shouldBe 587
      read("secondaryTime") shouldBe 0
      val team0 = reader(v8, team, offsetColumn = 1, sizeColumn = 3, typeColumn = 5, fieldColumn = 4)
      val team1 = reader(v8, team, offsetColumn = 2, sizeColumn = 3, typeColumn = 5, fieldColumn = 4)
      (team0("teamNumber"), team0("teamColor"), team0("score")) shouldBe ((12, 0, 2))
      (team1("teamNumber"), team1("teamColor"), team1("score")) shouldBe ((7, 1, 1))
      val player3 = offsetOf(team, "player[0..10]", 1) + 2 * (3 - 1)
      (v8(player3), v8(player3 + 1)) shouldBe ((1.toByte, 25.toByte))
    }
    "give version 7 offsets that add up to 116 bytes and read the real packet right" in {
      val packet = table("gc-v7")
      val team = table("gc-v7-team")
      v7.length shouldBe 116
      contiguous(packet, offsetColumn = 0, sizeColumn = 1) shouldBe 116
      contiguous(team, offsetColumn = 0, sizeColumn = 3) shouldBe 48
      teamOffsetsAgree(packet, team, fieldColumn = 2)
      val read = reader(v7, packet, offsetColumn = 0, sizeColumn = 1, typeColumn = 3, fieldColumn = 2)
      read("version") shouldBe 7
      read("playersPerTeam") shouldBe 6
      read("gameState") shouldBe 3
      read("firstHalf") shouldBe 1
      read("kickOffTeam") shouldBe 1
      read("dropInTime") shouldBe -1
      read("secsRemaining") shouldBe 587
      val team0 = reader(v7, team, offsetColumn = 1, sizeColumn = 3, typeColumn = 5, fieldColumn = 4)
      val team1 = reader(v7, team, offsetColumn = 2, sizeColumn = 3, typeColumn = 5, fieldColumn = 4)
      (team0("teamNumber"), team0("teamColor"), team0("score")) shouldBe ((12, 0, 2))
      (team1("teamNumber"), team1("teamColor"), team1("score")) shouldBe ((7, 1, 1))
      val player3 = offsetOf(team, "player[0..10]", 1) + 4 * (3 - 1)
      littleEndian(v7, player3, 2) shouldBe 1
      littleEndian(v7, player3 + 2, 2) shouldBe 25
    }
    "build the RGrt return packet as its table says" in {
      val packet = bytes("gc-return-alive")
      packet.toVector shouldBe ("RGrt".getBytes(US_ASCII) ++ Array[Byte](2, 12, 3, 2)).toVector
      val layout = table("gc-return")
      contiguous(layout, offsetColumn = 0, sizeColumn = 1) shouldBe packet.length
      val read = reader(packet, layout, offsetColumn = 0, sizeColumn = 1, typeColumn = 3, fieldColumn = 2)
      (read("version"), read("team"), read("player"), read("message")) shouldBe ((2, 12, 3, 2))
      classify(packet) shouldBe GameController
    }
  }

  "The GameController examples and tables of versions 19 and 12" should {
    lazy val v19 = vector("v19-playing.bin")
    lazy val v12 = vector("v12-playing.bin")

    "quote the first bytes of the built packets" in {
      bytes("gc-v19-header").toVector shouldBe v19.take(18).toVector
      bytes("gc-v12-header").toVector shouldBe v12.take(24).toVector
      classify(v19) shouldBe GameController
      classify(v12) shouldBe GameController
    }
    "give version 19 offsets that add up to 198 bytes and read the packet right" in {
      val packet = table("gc-v19")
      val team = table("gc-v19-team")
      contiguous(packet, offsetColumn = 0, sizeColumn = 1) shouldBe 198
      contiguous(team, offsetColumn = 0, sizeColumn = 3) shouldBe 90
      teamOffsetsAgree(packet, team, fieldColumn = 2)
      val read = reader(v19, packet, offsetColumn = 0, sizeColumn = 1, typeColumn = 3, fieldColumn = 2)
      (read("version"), read("packetNumber"), read("playersPerTeam"), read("stopped"), read("state"),
        read("setPlay")) shouldBe
        ((19, 4, 7, 1, 3, 5))
      (read("kickingTeam"), read("secsRemaining"), read("secondaryTime")) shouldBe ((7, 587, 30))
      val team0 = reader(v19, team, offsetColumn = 1, sizeColumn = 3, typeColumn = 5, fieldColumn = 4)
      val team1 = reader(v19, team, offsetColumn = 2, sizeColumn = 3, typeColumn = 5, fieldColumn = 4)
      (team0("teamNumber"), team0("goalkeeperColour"), team0("score"), team0("messageBudget")) shouldBe ((12, 2, 2,
        11800))
      (team1("teamNumber"), team1("fieldPlayerColour"), team1("score"), team1("messageBudget")) shouldBe ((7, 1, 1,
        11790))
      val player3 = offsetOf(team, "player[0..19]", 1) + 4 * (3 - 1)
      v19.slice(player3, player3 + 4).toVector shouldBe Vector[Byte](9, 25, 1, 1)
      GameControllerCodec.decodeControl(v19).map(_.version) shouldBe Right(GameControlVersion.V19)
    }
    "give version 20 offsets that add up to 158 bytes, and its penalties by the codec's codes and names" in {
      contiguous(table("gc-v20"), offsetColumn = 0, sizeColumn = 1) shouldBe 158
      GameControlVersion.V20.packetBytes shouldBe 158
      def letters(name: String) = name.takeWhile(_ != '(').replace(" or ", " ").filter(_.isLetter)
      val rows = table("gc-v20-penalty").rows
      rows.map(_(0).toInt) shouldBe Hsl20Penalty.known.map(_.code)
      rows.map(r => letters(r(1))) shouldBe Hsl20Penalty.known.map(p => letters(PlayerPenalty(p, 0).name))
    }
    "give version 12 offsets that add up to 688 bytes and read the packet right" in {
      val packet = table("gc-v12")
      val team = table("gc-v12-team")
      contiguous(packet, offsetColumn = 0, sizeColumn = 1) shouldBe 688
      contiguous(team, offsetColumn = 0, sizeColumn = 3) shouldBe 332
      teamOffsetsAgree(packet, team, fieldColumn = 2)
      val read = reader(v12, packet, offsetColumn = 0, sizeColumn = 1, typeColumn = 3, fieldColumn = 2)
      (read("version"), read("packetNumber"), read("playersPerTeam"), read("state"), read("kickOffTeam")) shouldBe ((12,
        4, 4, 3, 7))
      (read("secondaryState"), read("dropInTime"), read("secsRemaining")) shouldBe ((4, 65535, 587))
      val team0 = reader(v12, team, offsetColumn = 1, sizeColumn = 3, typeColumn = 5, fieldColumn = 4)
      val team1 = reader(v12, team, offsetColumn = 2, sizeColumn = 3, typeColumn = 5, fieldColumn = 4)
      (team0("teamNumber"), team0("score"), team1("teamNumber"), team1("score")) shouldBe ((12, 2, 7, 1))
      val player1 = offsetOf(team, "player[0..10]", 1)
      val player3 = player1 + 6 * (3 - 1)
      v12.slice(player3, player3 + 6).toVector shouldBe Vector[Byte](31, 25, 1, 1, 0, 0)
      v12(player1 + 5) shouldBe 1.toByte // player 1 is the goalkeeper
      GameControllerCodec.decodeControl(v12).map(_.version) shouldBe Right(GameControlVersion.V12)
    }
    "build the RGrt version-4 status message as its table says" in {
      val packet = bytes("gc-status-example")
      val layout = table("gc-status")
      contiguous(layout, offsetColumn = 0, sizeColumn = 1) shouldBe 32
      GameControllerCodec.decodeStatus(packet) shouldBe
        Right(ReturnStatus(3, 12, fallen = false, (1000f, -500f, 1.5f), 2f, (250f, -100f)))
      val read = reader(packet, layout, offsetColumn = 0, sizeColumn = 1, typeColumn = 3, fieldColumn = 2)
      (read("version"), read("playerNum"), read("teamNum"), read("fallen")) shouldBe ((4, 3, 12, 0))
      classify(packet) shouldBe GameController
    }
    "say which states close the gate, as CompetitionGate decides" in {
      val rows = table("gc-gate").rows
      rows.map(_(0)) shouldBe Seq("20", "19", "12", "8", "7", "shared header", "unreadable")
      rows.filter(_(0) != "unreadable").foreach { row =>
        val closing = "(\\d) [A-Z]+".r.findAllMatchIn(row(2)).map(_.group(1).toInt).toSet
        val opening = "(\\d) [A-Z]+".r.findAllMatchIn(row(3)).map(_.group(1).toInt).toSet
        closing shouldBe Set(1, 2, 3)
        (closing ++ opening) shouldBe GameState.known.map(_.code).toSet
        closing.foreach(c =>
          naogateway.gateway.gamecontroller.CompetitionGate.gameRunning(GameState.fromCode(c)) shouldBe true)
        opening.foreach(c =>
          naogateway.gateway.gamecontroller.CompetitionGate.gameRunning(GameState.fromCode(c)) shouldBe false)
      }
      naogateway.gateway.gamecontroller.CompetitionGate.closes(
        naogateway.api.GameReading.Unreadable("any")) shouldBe true
      rows.last(3) should include("never by itself")
      // The rule's wait to open is the reference configuration's, and longer than the GameController's interval.
      val openAfter = com.typesafe.config.ConfigFactory.load().getDuration("naogateway.game-controller.gate-open-after")
      new String(java.nio.file.Files.readAllBytes(doc.path), "UTF-8") should include(
        s"`naogateway.game-controller.gate-open-after` (${openAfter.getSeconds} s by default")
      openAfter.toMillis should be > 500L
    }
    "give the monitor exchange with the bytes and ports the gateway uses" in {
      val rows = table("gc-monitor").rows.map(r => r(0) -> r).toMap
      rows("request")(1) should startWith("RGTr then version 00 (5 bytes)")
      GameControllerCodec.monitorRequest.toVector shouldBe ("RGTr".getBytes(US_ASCII) :+ 0.toByte).toVector
      rows("request")(2) should include("3636")
      rows("true state")(1) should include("RGTD")
      rows("forwarded status")(2) should include("3940")
      val defaults = com.typesafe.config.ConfigFactory.load().getConfig("naogateway.game-controller.monitor")
      (defaults.getInt("request-port"), defaults.getInt("status-port"), defaults.getBoolean("enabled")) shouldBe ((3636,
        3940, false))
    }
    "give the message budget rules the gateway counts with" in {
      val rules = table("gc-budget").rows.map(r => r(0) -> r(1)).toMap
      val defaults = naogateway.gateway.gamecontroller.TeamMessageSettings()
      rules("budget per team per game") should startWith(s"${defaults.perGame} messages")
      rules("per minute of additional time") should startWith(s"${defaults.perExtraMinute} more")
      rules("at the start of extra time") should startWith(s"${defaults.perExtraTime} more")
      rules("largest message") shouldBe s"${defaults.maxBytes} bytes"
      naogateway.gateway.GatewaySettings.fromConfig(com.typesafe.config.ConfigFactory.load().getConfig("naogateway"))
        .teamMessages shouldBe defaults
    }
  }

  "The secure-stream examples" should {
    "show a data segment and a pure ACK" in {
      bytes("stream-data").toVector shouldBe (Array[Byte](3, 5) ++ "Lorem".getBytes(US_ASCII)).toVector
      bytes("stream-pure-ack").toVector shouldBe Vector[Byte](6, 9)
      classify(bytes("stream-data")) shouldBe Segment
      classify(bytes("stream-pure-ack")) shouldBe Segment
    }
    "carry a whole FU-Remote frame as the payload of an RPC segment" in {
      val segment = bytes("stream-data-rpc")
      segment.take(2).toVector shouldBe Vector[Byte](0, 20)
      segment.drop(2).toVector shouldBe bytes("rpc-request-walk").toVector
      classify(segment) shouldBe Segment
    }
    "follow the stop-and-wait rules in the thesis sequence (W = 1, maxSeq 20)" in {
      val gateway = new Endpoint(maxSeq = 20, window = 1, next = 0, last = 20)
      val robot = new Endpoint(maxSeq = 20, window = 1, next = 0, last = 20)
      val hops = Vector(
        Hop(G, New("Lo")),
        Hop(R, Ack),
        Hop(G, New("re"), lost = true),
        Hop(G, Resend(Timeout)),
        Hop(R, Ack, lost = true),
        Hop(G, Resend(Timeout)),
        Hop(R, Ack),
        Hop(G, New("m")),
        Hop(R, New("OK")),
        Hop(G, Ack),
        Hop(R, IdleAck),
        Hop(G, IdleAck)
      )
      replay(lines("stream-window1"), hops, gateway, robot)
      robot.delivered.mkString shouldBe "Lorem"
      gateway.delivered.mkString shouldBe "OK"
      (gateway.inFlight, robot.inFlight) shouldBe ((0, 0))
    }
    "follow the selective-repeat rules in the window-4 sequence" in {
      val gateway = new Endpoint(maxSeq = 20, window = 4, next = 5, last = 20)
      val robot = new Endpoint(maxSeq = 20, window = 4, next = 0, last = 4)
      val hops = Vector(
        Hop(G, New("a")),
        Hop(G, New("b"), lost = true),
        Hop(G, New("c")),
        Hop(G, New("d"), lost = true),
        Hop(R, Ack),
        Hop(R, Ack),
        Hop(G, New("e")),
        Hop(R, Ack),
        Hop(G, Resend(DuplicateAcks)),
        Hop(R, Ack),
        Hop(G, Resend(PartialAck)),
        Hop(R, Ack)
      )
      replay(lines("stream-window4"), hops, gateway, robot)
      robot.delivered.mkString shouldBe "abcde"
      gateway.inFlight shouldBe 0
    }
    "announce two expired segments one per round trip in the skip-notice sequence (W = 4)" in {
      val gateway = new Endpoint(maxSeq = 20, window = 4, next = 0, last = 20)
      val robot = new Endpoint(maxSeq = 20, window = 4, next = 0, last = 20)
      val hops = Vector(
        Hop(G, New("a"), lost = true),
        Hop(G, New("b"), lost = true),
        Hop(G, New("c")),
        Hop(R, Ack),
        Hop(G, Expire(0, 1)),
        Hop(R, Ack),
        Hop(G, Resend(ExpiredHead)),
        Hop(R, Ack)
      )
      replay(lines("stream-skip"), hops, gateway, robot)
      robot.delivered.mkString shouldBe "c"
      robot.skipped shouldBe 2
      gateway.inFlight shouldBe 0
    }
    "give the skip-notice sequence exactly as the gateway's SecureStream sends it" in {
      import naogateway.wire.stream.{SecureStream, StreamSettings}
      def ms(n: Long): Long = n * 1000000L
      def sent(step: SecureStream.Step): Vector[Vector[Byte]] =
        step.outputs.collect { case SecureStream.Transmit(d) => d.toVector }
      def ok(r: Either[SecureStream.SendRefused, SecureStream.Step]): SecureStream.Step =
        r.fold(e => fail(e.describe), identity)
      val settings = StreamSettings(window = 4, maxSeq = 20)
      val a = ok(SecureStream.initial(settings, 0L).send("a".getBytes(US_ASCII), 1L, Some(ms(100)), 0L))
      val b = ok(a.state.send("b".getBytes(US_ASCII), 2L, Some(ms(100)), 0L))
      val c = ok(b.state.send("c".getBytes(US_ASCII), 3L, None, 0L))
      val keep = SecureStream.initial(settings, 0L).receive(sent(c).head.toArray, ms(5))
      val dup = c.state.receive(sent(keep).head.toArray, ms(10))
      val expiry = dup.state.tick(ms(100))
      val skip0 = keep.state.receive(sent(expiry).head.toArray, ms(105))
      val notice1 = expiry.state.receive(sent(skip0).head.toArray, ms(110))
      val skip1 = skip0.state.receive(sent(notice1).head.toArray, ms(115))
      val done = notice1.state.receive(sent(skip1).head.toArray, ms(120))
      (sent(a) ++ sent(b) ++ sent(c) ++ sent(keep) ++ sent(dup) ++ sent(expiry) ++ sent(skip0) ++ sent(notice1) ++
        sent(skip1)) shouldBe lines("stream-skip").map(_.toVector)
      expiry.outputs.collect { case SecureStream.Expired(id) => id } shouldBe Vector(1L, 2L)
      skip1.outputs.collect { case SecureStream.Deliver(p) => new String(p, US_ASCII) } shouldBe Vector("c")
      skip1.state.stats.skipped shouldBe 2
      done.outputs.collect { case SecureStream.Acknowledged(id) => id } shouldBe Vector(3L)
      done.state.inFlight shouldBe 0
    }
  }

  "The GS1500M serial examples" should {
    "frame the thesis Status as ESC Z cid len4 data" in {
      val serial = bytes("serial-send-status")
      new String(serial.take(7), US_ASCII) shouldBe "\u001bZ00030"
      serial.drop(7).toVector shouldBe bytes("status-legacy").toVector
    }
    "frame a UDP-server datagram as ESC y cid ip SPACE port TAB len4 data" in {
      val serial = bytes("serial-receive-udp-server")
      val tab = serial.indexOf('\t'.toByte)
      new String(serial.take(tab + 5), US_ASCII) shouldBe "\u001by0192.168.1.10 11011\t0020"
      val data = serial.drop(tab + 5)
      data.length shouldBe 20
      data.toVector shouldBe bytes("debug-option-pull").toVector
    }
  }

  private def replay(docLines: Vector[Array[Byte]], hops: Vector[Hop], gateway: Endpoint, robot: Endpoint): Unit = {
    docLines.length shouldBe hops.length
    hops.zip(docLines).zipWithIndex.foreach { case ((hop, line), i) =>
      val (from, to) = if (hop.from == G) (gateway, robot) else (robot, gateway)
      val segment = hop.action match {
        case New(payload)      => from.sendNew(payload)
        case Resend(cause)     => from.resend(cause)
        case Expire(seqs @ _*) => from.expire(seqs)
        case Ack               => from.ack(idle = false)
        case IdleAck           => from.ack(idle = true)
      }
      withClue(s"datagram ${i + 1} (${hop.from} ${hop.action}): ") {
        line.toVector shouldBe segment.toVector
        classify(line) shouldBe Segment
      }
      if (!hop.lost) to.receive(segment)
    }
  }

  /** The simulated robot 1 with default settings, booted at 0 and advanced in 200 ms steps up to 5000 ms. */
  private def keepAliveAt5000: (FirmwareState, Vector[Outgoing]) =
    // Servo telemetry off, as 9.13 says: the example shows Status and RobotHealth alone.
    (0 to 5000 by 200).foldLeft((RobotFirmware.boot(
          FirmwareSettings(robotId = 1, servoTelemetryInterval = scala.concurrent.duration.Duration.Zero), 0L),
        Vector.empty[Outgoing])) {
      case ((state, _), millis) => RobotFirmware.advance(state, millis * 1000000L)
    }

  private def vector(name: String): Array[Byte] = naogateway.wire.gamecontroller.GameControllerVectors.bytes(name)

  /** Checks that the rows' offsets follow each other without gap or overlap from 0; returns the total size. */
  private def contiguous(t: Table, offsetColumn: Int, sizeColumn: Int): Int =
    t.rows.foldLeft(0) { (expected, row) =>
      withClue(s"table ${t.tag}, row ${row.mkString(" | ")}: ") { row(offsetColumn).toInt shouldBe expected }
      expected + row(sizeColumn).toInt
    }

  /** The absolute columns of a TeamInfo table must be the team's offset in the packet plus the relative offset. */
  private def teamOffsetsAgree(packet: Table, team: Table, fieldColumn: Int): Unit = {
    val base0 = offsetOf(packet, "team[0]", 0, fieldColumn)
    val base1 = offsetOf(packet, "team[1]", 0, fieldColumn)
    team.rows.foreach { row =>
      withClue(s"table ${team.tag}, row ${row.mkString(" | ")}: ") {
        row(1).toInt shouldBe base0 + row(0).toInt
        row(2).toInt shouldBe base1 + row(0).toInt
      }
    }
    packet.rows.find(_(fieldColumn) == "team[0]").get.apply(1).toInt shouldBe team.rows.map(_(3).toInt).sum
  }

  private def offsetOf(t: Table, field: String, offsetColumn: Int, fieldColumn: Int = 4): Int =
    t.rows.find(_(fieldColumn) == field).getOrElse(fail(s"table ${t.tag} has no field $field"))(offsetColumn).toInt

  /** Reads a named little-endian field of `packet` at the offset and size its table row gives. */
  private def reader(packet: Array[Byte], t: Table, offsetColumn: Int, sizeColumn: Int, typeColumn: Int,
      fieldColumn: Int): String => Int = field => {
    val row = t.rows.find(_(fieldColumn) == field).getOrElse(fail(s"table ${t.tag} has no field $field"))
    val value = littleEndian(packet, row(offsetColumn).toInt, row(sizeColumn).toInt)
    if (row(typeColumn).startsWith("i") && value >= (1 << (8 * row(sizeColumn).toInt - 1)))
      value - (1 << (8 * row(sizeColumn).toInt))
    else value
  }
}

object ProtocolDocSpec {

  final case class FrameExample(contents: MessageContents, form: HeaderForm = HeaderForm.Legacy, gzip: Boolean = false)

  private val workedStatus =
    MessageContents(robotId = 1, status = Some(Status(teamID = Some(1), activeAgent = Some("AgentTest"))))

  private def float(value: Float) = MixedValue(float = Some(value))

  /** The region of the HaViMo example: colour class 2, 50 pixels, centre (80, 60). */
  val exampleRegion: HaViMoRegion = HaViMoRegion(index = 1, colour = 2, pixels = 50, sumX = 4000, sumY = 3000,
    maxX = 84, minX = 76, maxY = 64, minY = 56)

  /** What each FU-Remote frame example of the document must decode to. */
  val FrameExamples: ListMap[String, FrameExample] = ListMap(
    "status-legacy" -> FrameExample(workedStatus),
    "status-compact" -> FrameExample(workedStatus, HeaderForm.Compact),
    "status-gzip" -> FrameExample(workedStatus, gzip = true),
    "rpc-request-walk" -> FrameExample(MessageContents(robotId = 1,
        rpcRequest = Some(
          Request("motion", "walk", Seq(float(0.2f), float(0.0f), float(0.5f)), callId = Some(7))
        ))),
    "rpc-response-walk" -> FrameExample(MessageContents(robotId = 1,
        rpcResponse = Some(
          Response(returnval = Some(MixedValue(bool = Some(true))), callId = Some(7))
        ))),
    "rpc-request-probe" -> FrameExample(MessageContents(robotId = 1,
        rpcRequest = Some(
          Request("heartbeat", "probe", callId = Some(8))
        ))),
    "rpc-response-unknown" -> FrameExample(MessageContents(robotId = 1,
        rpcResponse = Some(
          Response(error = Some("unknown method: heartbeat.probe"), callId = Some(8))
        ))),
    "debug-option-pull" -> FrameExample(MessageContents(robotId = 1,
        debuggingCommands = Some(
          DebuggingCommands(optionPull = Some(true))
        ))),
    "debug-option-push" -> FrameExample(MessageContents(
        robotId = 1,
        debuggingCommands = Some(
          DebuggingCommands(optionPush = Some(DebuggingOptionList(Seq(
                DebuggingOption("havimo.regions", Some(DebuggingOptionType.HAVIMO_REGIONS), Some(true)),
                DebuggingOption("havimo.grid", Some(DebuggingOptionType.HAVIMO_GRID), Some(false)),
                DebuggingOption("text", Some(DebuggingOptionType.TEXT), Some(false))
              ))))
        )
      )),
    "debug-option-enable" -> FrameExample(MessageContents(robotId = 1,
        debuggingCommands = Some(
          DebuggingCommands(optionEnable = Some(DebuggingOptionNames(Seq("havimo"))))
        ))),
    "debug-data-text" -> FrameExample(MessageContents(robotId = 1,
        debugData = Some(
          DebugData("text", Some(5000L), DebugData.Data.Text(DebugText("ready")))
        ))),
    "keep-alive" -> FrameExample(MessageContents(
        robotId = 1,
        status = Some(Status(
            timestamp = Some(5000L),
            teamID = Some(1),
            timeOnline = Some(5),
            robotPosition = Some(Position(x = Some(-1000), y = Some(0), rotation = Some(0.0f))),
            activeAgent = Some("SimAgent"),
            activeRole = Some("striker"),
            currentState = Some("sit")
          )),
        robotHealth = Some(RobotHealth(batteryVoltage = Some(12.399f), posture = Some("sit"), uptimeMs = Some(5000),
            bootId = Some(1)))
      )),
    "havimo-regions" -> FrameExample(MessageContents(robotId = 1,
        havimoRegions = Some(
          HaViMoRegionFrame(42, Some(5000L),
            Some(ByteString.copyFrom(HaViMo.encodeRegions(Seq(exampleRegion)).toOption.get)))
        )))
  )

  val ExampleTags: Set[String] = FrameExamples.keySet ++ Set(
    "gc-v8-header",
    "gc-v7-header",
    "gc-return-alive",
    "gc-v19-header",
    "gc-v12-header",
    "gc-status-example",
    "stream-data",
    "stream-pure-ack",
    "stream-data-rpc",
    "serial-send-status",
    "serial-receive-udp-server",
    "signed-status",
    "signed-status-mac-input",
    "signed-option-pull",
    "robot-key-1"
  )
  val DatagramTags: Set[String] = Set("stream-window1", "stream-window4", "stream-skip")
  val TableTags: Set[String] =
    Set(
      "extension-keys",
      "extension-numbers",
      "debug-options",
      "gc-v8",
      "gc-v8-team",
      "gc-v7",
      "gc-v7-team",
      "gc-return",
      "gc-v19",
      "gc-v19-team",
      "gc-v20",
      "gc-v20-penalty",
      "gc-v12",
      "gc-v12-team",
      "gc-status",
      "gc-gate",
      "gc-budget",
      "gc-monitor"
    )

  // ---- reading the document ----

  /** A hex block: `example` blocks are one datagram over any number of lines, `datagrams` blocks one per line.
    * `annotation` is the table right below the block (before the next heading or marker), header row included.
    */
  final case class HexBlock(kind: String, tag: String, lines: Vector[Array[Byte]], lineNumber: Int,
      annotation: Option[Vector[Vector[String]]]) {
    def bytes: Array[Byte] = lines.flatten.toArray
  }

  /** A markdown table's body rows, cells trimmed and without backticks. */
  final case class Table(tag: String, rows: Vector[Vector[String]], lineNumber: Int)

  final class ProtocolDoc(val path: Path, val blocks: Vector[HexBlock], val tables: Vector[Table]) {
    def block(tag: String): Either[String, HexBlock] =
      blocks.find(_.tag == tag).toRight(s"$path has no block tagged $tag")
    def table(tag: String): Either[String, Table] =
      tables.find(_.tag == tag).toRight(s"$path has no table tagged $tag")
  }

  object ProtocolDoc {

    /** Forked tests run in the module folder (sim/), an sbt shell in the checkout. */
    val Candidates: Seq[Path] = Seq(Paths.get("../../docs/protocol.md"), Paths.get("docs/protocol.md"))

    private val Marker = """^<!--\s*(example|datagrams|table):\s*([a-z0-9-]+)\s*-->\s*$""".r

    def load(): Either[String, ProtocolDoc] =
      Candidates.find(Files.isRegularFile(_)) match {
        case None =>
          Left(s"docs/protocol.md not found; looked at ${Candidates.map(_.toAbsolutePath.normalize).mkString(", ")}")
        case Some(path) => parse(path, Files.readAllLines(path, UTF_8).asScala.toVector)
      }

    def parse(path: Path, text: Vector[String]): Either[String, ProtocolDoc] = {
      val blocks = Vector.newBuilder[HexBlock]
      val tables = Vector.newBuilder[Table]
      val problems = Vector.newBuilder[String]
      text.zipWithIndex.foreach {
        case (Marker(kind, tag), at) =>
          val start = text.indexWhere(_.trim.nonEmpty, at + 1)
          if (kind == "table") {
            val rows = text.drop(start).takeWhile(_.trim.startsWith("|"))
            if (start < 0 || rows.length < 3) problems += s"line ${at + 1}: table $tag has no rows"
            else tables += Table(tag, rows.drop(2).map(cells), at + 1)
          } else if (start < 0 || text(start).trim != "```hex")
            problems += s"line ${at + 1}: $tag is not followed by ```hex"
          else {
            val body = text.drop(start + 1).takeWhile(_.trim != "```")
            if (start + 1 + body.length >= text.length) problems += s"line ${at + 1}: $tag's hex block is not closed"
            else {
              val parsed = body.zipWithIndex.filter(_._1.trim.nonEmpty).map { case (line, i) =>
                parseHex(line).left.map(p => s"line ${start + 2 + i}: $p")
              }
              parsed.collect { case Left(p) => p }.foreach(problems += _)
              val after = start + 2 + body.length
              val next = text.indexWhere(l => l.startsWith("|") || l.startsWith("#") || l.startsWith("<!--"), after)
              val annotation =
                if (next < 0 || !text(next).startsWith("|")) None
                else Some(text.drop(next).takeWhile(_.startsWith("|")).map(cells)).map(t => t.take(1) ++ t.drop(2))
              blocks += HexBlock(kind, tag, parsed.collect { case Right(b) => b }, at + 1, annotation)
            }
          }
        case (line, at) if line.trim.startsWith("<!--") && Seq("example", "datagrams", "table").exists(line.contains) =>
          problems += s"line ${at + 1}: malformed marker: $line"
        case _ => ()
      }
      val found = problems.result()
      if (found.nonEmpty) Left(s"$path: ${found.mkString("; ")}")
      else Right(new ProtocolDoc(path, blocks.result(), tables.result()))
    }

    private def cells(row: String): Vector[String] =
      row.trim.stripPrefix("|").stripSuffix("|").split('|').toVector.map(_.trim.replace("`", ""))
  }

  /** Space-separated bytes of two upper-case hex digits each. */
  def parseHex(line: String): Either[String, Array[Byte]] = {
    val tokens = line.trim.split("\\s+").toVector
    tokens.find(t => !t.matches("[0-9A-F]{2}")) match {
      case Some(bad) => Left(s"'$bad' is not a byte of two upper-case hex digits")
      case None      => Right(tokens.map(Integer.parseInt(_, 16).toByte).toArray)
    }
  }

  /** An annotation table with a column of bytes: `offset | bytes | …` or `# | from → to | bytes | …`. */
  def isByteTable(table: Vector[Vector[String]]): Boolean =
    table.headOption.exists(h =>
      h.headOption.contains("offset") && h.lift(1).contains("bytes") || h.lift(2).contains("bytes"))

  def varint(value: Long): Array[Byte] = {
    val out = Array.newBuilder[Byte]
    var rest = value
    while (rest >= 0x80) { out += ((rest & 0x7f) | 0x80).toByte; rest >>>= 7 }
    out += rest.toByte
    out.result()
  }

  def littleEndian(bytes: Array[Byte], at: Int, size: Int): Int =
    (0 until size).map(i => (bytes(at + i) & 0xff) << (8 * i)).sum

  // ---- datagram classes of section 3 ----

  sealed trait DatagramClass
  case object FuRemote extends DatagramClass
  case object GameController extends DatagramClass
  case object Segment extends DatagramClass
  case object Rejected extends DatagramClass

  def classify(d: Array[Byte]): DatagramClass = {
    def u(i: Int) = d(i) & 0xff
    if (d.length < 2 || d.length > WireLimits.MaxDatagramBytes) Rejected
    else if (u(0) == 0 && u(1) == WireLimits.FumanoidsOperation) FuRemote
    else if (d.length >= 4 && Set("RGme", "RGrt").contains(new String(d.take(4), US_ASCII))) GameController
    else if (u(0) < WireLimits.StreamSequenceLimit && u(1) < WireLimits.StreamSequenceLimit) Segment
    else Rejected
  }

  // ---- a reference model of the secure stream (section 11) ----
  //
  // It has no clock: timers are hops of the replay (Resend(Timeout), Expire), and the sequence-reuse rule (11.8) is
  // checked more strictly than it reads, against every retransmission in the replay rather than those of the last
  // round trip, so an example that passes does not depend on timing. Round-trip samples and the RTO are not modelled.

  sealed trait Side
  case object G extends Side
  case object R extends Side

  /** Why a sender sends its oldest unacknowledged segment again (or, if it has expired, a skip notice). */
  sealed trait Cause
  case object Timeout extends Cause
  case object DuplicateAcks extends Cause
  case object PartialAck extends Cause

  /** An ACK advanced base onto an expired segment: the skip notice for it goes out at once. */
  case object ExpiredHead extends Cause

  sealed trait Action
  final case class New(payload: String) extends Action
  final case class Resend(cause: Cause) extends Action

  /** The deadlines of these in-flight sequence numbers pass; the oldest is among them, so a skip notice goes out. */
  final case class Expire(seqs: Int*) extends Action
  case object Ack extends Action
  case object IdleAck extends Action

  final case class Hop(from: Side, action: Action, lost: Boolean = false)

  /** One end of a stream: sender state (base, next, recovery, expired segments) and receiver state (last in order, kept
    * segments). Skip notices are honoured, as by the gateway's endpoint.
    */
  final class Endpoint(maxSeq: Int, window: Int, next: Int, last: Int) {
    private val m = maxSeq + 1
    require(2 * window <= m)
    private var nextSeq = next
    private var base = next
    private var lastInOrder = last
    private val outstanding = mutable.Map.empty[Int, Array[Byte]]
    private val expired = mutable.Set.empty[Int]
    private val resent = mutable.Set.empty[Int]
    private val kept = mutable.Map.empty[Int, Array[Byte]]
    private var owedAcks = 0
    private var duplicateAcks = 0
    private var recoveryPoint: Option[Int] = None
    private var fastRetransmitDone = false
    private var partialAckPending = false
    private var noticeOwed = false
    val delivered: mutable.ArrayBuffer[String] = mutable.ArrayBuffer.empty
    var skipped: Int = 0

    private def mod(x: Int) = ((x % m) + m) % m
    def inFlight: Int = mod(nextSeq - base)
    private def headExpired: Boolean = inFlight > 0 && expired(base)

    /** Byte 0 of a pure ACK: the last ACK received, or one past it when the oldest segment has expired (11.7). */
    def announced: Int = if (headExpired) base else mod(base - 1)
    private def header(first: Int): Array[Byte] = Array(first.toByte, lastInOrder.toByte)

    def sendNew(payload: String): Array[Byte] = {
      require(inFlight < window, s"window full: $inFlight in flight")
      require(!resent(mod(nextSeq + window)), s"sequence-reuse rule: ${mod(nextSeq + window)} was resent")
      val bytes = payload.getBytes(US_ASCII)
      require(bytes.length >= 1 && bytes.length <= 1398, s"payload of ${bytes.length} bytes")
      outstanding(nextSeq) = bytes
      val segment = header(nextSeq) ++ bytes
      nextSeq = mod(nextSeq + 1)
      owedAcks = 0 // the ACK byte is piggybacked
      segment
    }

    def resend(cause: Cause): Array[Byte] = {
      require(inFlight > 0, "nothing to resend")
      cause match {
        case Timeout => ()
        case DuplicateAcks =>
          require(duplicateAcks >= 2 && !fastRetransmitDone, s"$duplicateAcks duplicate ACKs do not allow a resend")
          fastRetransmitDone = true
        case PartialAck  => require(partialAckPending, "no partial ACK to answer")
        case ExpiredHead => require(noticeOwed, "no ACK advanced onto an expired segment")
      }
      partialAckPending = false
      noticeOwed = false
      if (cause != ExpiredHead && recoveryPoint.isEmpty) recoveryPoint = Some(mod(nextSeq - 1))
      owedAcks = 0
      if (headExpired) header(announced) // an expired segment's data is never sent again: a skip notice instead
      else {
        resent += base
        header(base) ++ outstanding(base)
      }
    }

    def expire(seqs: Seq[Int]): Array[Byte] = {
      require(!headExpired, "the oldest segment has expired already")
      seqs.foreach(s => require(mod(s - base) < inFlight && !expired(s), s"$s is not an unexpired segment in flight"))
      expired ++= seqs
      require(headExpired, "the oldest segment did not expire: no skip notice goes out")
      header(announced)
    }

    def ack(idle: Boolean): Array[Byte] = {
      require(idle || owedAcks > 0, "nothing received that is answered")
      if (!idle) owedAcks -= 1
      header(announced)
    }

    private def deliverKept(): Unit =
      while (kept.contains(mod(lastInOrder + 1))) {
        lastInOrder = mod(lastInOrder + 1)
        delivered += new String(kept.remove(lastInOrder).get, US_ASCII)
      }

    def receive(segment: Array[Byte]): Unit = {
      val first = segment(0) & 0xff
      val ackByte = segment(1) & 0xff
      val acked = mod(ackByte - base)
      if (inFlight > 0 && acked < inFlight) {
        val covered = recoveryPoint.exists(rp => mod(rp - base) <= acked)
        (0 to acked).foreach { i => outstanding.remove(mod(base + i)); expired -= mod(base + i) }
        base = mod(ackByte + 1)
        duplicateAcks = 0
        if (covered) { recoveryPoint = None; fastRetransmitDone = false; partialAckPending = false }
        else if (recoveryPoint.isDefined) partialAckPending = true
        noticeOwed = headExpired
      } else if (segment.length == 2 && inFlight > 0 && ackByte == mod(base - 1)) duplicateAcks += 1
      if (segment.length > 2) {
        val ahead = mod(first - mod(lastInOrder + 1))
        if (ahead <= window - 1) {
          kept.getOrElseUpdate(first, segment.drop(2))
          deliverKept()
          owedAcks += 1
        } else if (ahead >= m - window) owedAcks += 1 // a duplicate: re-acknowledge, do not deliver
      } else if (first == mod(lastInOrder + 1)) {
        // A skip notice for exactly the next expected number: that segment expired at its sender.
        lastInOrder = first
        kept.remove(first) match {
          case Some(payload) => delivered += new String(payload, US_ASCII)
          case None          => skipped += 1
        }
        deliverKept()
        owedAcks += 1
      }
    }
  }
}
