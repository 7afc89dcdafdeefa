package naogateway.integration

import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.{GatewayAccess, RobotAccess}
import naogateway.api.{CallResult, GameSource, GameStateUpdated, RobotFailure, RobotOnline}
import naogateway.gateway.Rejection
import naogateway.gateway.robot.{Outbox, RobotEffects}
import naogateway.wire.{RpcCall, RpcValue}
import naogateway.wire.gamecontroller._

/** The competition gate in a real gateway for every GameController version a team may meet (docs/protocol.md 10.7): it
  * starts closed, READY, SET and PLAYING close it at once, a while of INITIAL or FINISHED opens it, a packet the
  * trusted GameController sends that cannot be read closes it and says why (fail safe), while one from elsewhere
  * changes nothing, and a later version is read by its shared header.
  */
class EveryVersionGateSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  private def call(c: RobotEffects.Connected, name: String, params: RpcValue*): CallResult = {
    val probe = createTestProbe[CallResult]()
    val (module, method) = name.span(_ != '.')
    c.response ! RobotAccess.Call(RpcCall(module, method.drop(1), params.toVector), probe.ref)
    probe.receiveMessage(10.seconds)
  }

  private def vector(file: String): GameControlData =
    GameControllerCodec.decodeControl(GameControllerVectors.bytes(file)).fold(e => fail(e.describe), identity)

  /** A packet of the vector's version in `state`, numbered `number` where the version has packet numbers, every other
    * field as the vector has it.
    */
  private def inState(d: GameControlData, state: GameState, number: Int = 1): Array[Byte] = {
    val n = number & 0xff
    val moved = d match {
      case v: ControlData2014  => v.copy(gameState = state, packetNumber = v.packetNumber.map(_ => n))
      case v: HlControlData    => v.copy(gameState = state, packetNumber = n)
      case v: HslControlData   => v.copy(gameState = state, packetNumber = n)
      case v: Hsl20ControlData => v.copy(gameState = state, packetNumber = n)
    }
    GameControllerCodec.encodeControl(moved).fold(e => fail(e.describe), identity)
  }

  private val versions = Seq(
    GameControlVersion.V20 -> vector("v20-playing.bin"),
    GameControlVersion.V19 -> vector("v19-playing.bin"),
    GameControlVersion.V12 -> vector("v12-playing.bin"),
    GameControlVersion.V8 -> vector("v8-playing.bin"),
    GameControlVersion.V7 -> vector("v7-playing.bin")
  )

  private val competition =
    "competition.enabled = on\ngame-controller.trusted-sources = [\"127.0.0.1\"]\ngame-controller.gate-open-after = 1s"

  /** Sends `packet` in `state` every 200 ms with packet numbers one after the other until the gate opens; at most 40.
    */
  private def openWith(f: GatewayFixture, send: Array[Byte] => Unit, packet: GameControlData, state: GameState,
      from: Int): Int = {
    var n = from
    while (!f.traffic().gateOpen) {
      if (n - from >= 40) fail(s"version ${packet.version.number}: the gate did not open in $state")
      send(inState(packet, state, n))
      n += 1
      Thread.sleep(200)
    }
    n
  }

  "A gateway in competition mode" must {
    "start closed, close the gate in READY, SET and PLAYING of versions 20, 19, 12, 8 and 7, refusing calls, and open " +
      "it only after a while of INITIAL or FINISHED" in {
        val f = new GatewayFixture(testKit, competition)
        val gc = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
        def send(bytes: Array[Byte]): Unit = { gc.send(ByteBuffer.wrap(bytes), f.addresses.gameController.get); () }
        try {
          f.robot(8)
          f.awaitEvent(10.seconds) { case RobotOnline(8, _) => () }
          val connected = f.connect(8)
          f.traffic().gateReason shouldBe Some(
            "no packet from the trusted GameController yet (competition mode starts closed)")
          call(connected, "system.ping").result shouldBe Left(RobotFailure.RuleGate(Outbox.NoSendingWhileGameRuns))
          var number = openWith(f, send, versions.head._2, GameState.Initial, 1)
          // A loaded machine may take the robot offline for a moment while its JVM warms up: it comes back by itself.
          eventually(timeout(20.seconds)) { call(connected, "system.ping").result.isRight shouldBe true }
          versions.foreach { case (version, packet) =>
            Seq(GameState.Ready, GameState.Set, GameState.Playing).foreach { state =>
              send(inState(packet, state, number))
              number += 1
              f.awaitEvent(10.seconds) {
                case GameStateUpdated(d) if d.version == version && d.gameState == state => ()
              }
              withClue(s"version ${version.number} $state: ") {
                val t = f.traffic()
                t.gateOpen shouldBe false
                t.gateReason shouldBe Some(s"the game is running ($state)")
                eventually(timeout(10.seconds)) {
                  call(connected, "system.ping").result shouldBe Left(
                    RobotFailure.RuleGate(Outbox.NoSendingWhileGameRuns))
                }
              }
            }
            send(inState(packet, GameState.Finished, number))
            number += 1
            f.awaitEvent(10.seconds) {
              case GameStateUpdated(d) if d.version == version && d.gameState == GameState.Finished => ()
            }
            withClue(s"version ${version.number} FINISHED: ") {
              // One FINISHED does not open it: only a while of them does (docs/protocol.md 10.7).
              f.traffic().gateOpen shouldBe false
              f.traffic().gateReason.getOrElse("") should startWith("opening once the game has not run for a while")
              number = openWith(f, send, packet, GameState.Finished, number)
              eventually(timeout(20.seconds)) { call(connected, "system.ping").result.isRight shouldBe true }
            }
          }
        } finally {
          gc.close()
          f.stop()
        }
      }

    "close the gate on a packet of the trusted GameController it cannot read, say why once, and ignore one from " +
      "elsewhere; read a later version by its shared header, with a warning" in {
        val f = new GatewayFixture(testKit, competition)
        val gc = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
        val stranger = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.2", 0))
        val target = f.addresses.gameController.get
        def send(bytes: Array[Byte]): Unit = { gc.send(ByteBuffer.wrap(bytes), target); () }
        // An older unknown layout: RGme, a u8 version 14, 200 bytes; and a later one: version 21, 170 bytes, whose
        // first 18 bytes are those of versions 18 to 20.
        val unknown = "RGme".getBytes("US-ASCII") ++ Array[Byte](14) ++ new Array[Byte](195)
        val later = java.util.Arrays.copyOf(GameControllerVectors.bytes("v20-playing.bin").updated(4, 21.toByte), 170)
        try {
          f.robot(9)
          f.awaitEvent(10.seconds) { case RobotOnline(9, _) => () }
          val connected = f.connect(9)
          var number = openWith(f, send, versions.head._2, GameState.Initial, 1)
          stranger.send(ByteBuffer.wrap(unknown), target)
          eventually(timeout(20.seconds)) { call(connected, "system.ping").result.isRight shouldBe true }
          f.traffic().gateOpen shouldBe true

          (1 to 3).foreach(_ => send(unknown))
          eventually(timeout(10.seconds)) {
            val t = f.traffic()
            t.gateOpen shouldBe false
            t.gateReason shouldBe Some(
              "the trusted GameController's packet cannot be read (RGme of unknown version 14, 200 bytes; 3 so far)")
          }
          eventually(timeout(10.seconds)) {
            call(connected, "system.ping").result shouldBe Left(RobotFailure.RuleGate(Outbox.NoSendingWhileGameRuns))
          }
          f.stats().rejected.get(Rejection.BadGameControllerPacket.name) shouldBe Some(3L)
          f.stats().rejected.get(Rejection.UntrustedGameController.name) shouldBe Some(1L)
          // Readable packets open it again, by the rule: a while of them.
          number = openWith(f, send, versions.head._2, GameState.Initial, number)

          // Version 21: its shared header says PLAYING, so the gate closes, and the source warns.
          send(later.updated(5, number.toByte))
          number += 1
          eventually(timeout(10.seconds)) {
            f.traffic().gateReason shouldBe Some(
              "the game is running (Playing, read from the shared header of unknown version 21)")
          }
          val source = createTestProbe[GameSource]()
          f.gateway ! GatewayAccess.GetGameSource(source.ref)
          source.receiveMessage().warnings.exists(_.startsWith("GameController version 21 (170 bytes) is not known"))
            .shouldBe(true)
          // ... and its INITIAL opens it after a while, as a known version's does.
          var n = number
          while (!f.traffic().gateOpen && n - number < 40) {
            send(later.updated(5, (n & 0xff).toByte).updated(10, 0.toByte))
            n += 1
            Thread.sleep(200)
          }
          f.traffic().gateOpen shouldBe true
        } finally {
          gc.close()
          stranger.close()
          f.stop()
        }
      }
  }
}
