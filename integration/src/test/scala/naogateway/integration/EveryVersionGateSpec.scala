package naogateway.integration

import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway._
import naogateway.wire.{RpcCall, RpcValue}
import naogateway.wire.gamecontroller._

/** The competition gate in a real gateway for every GameController version a team may meet: READY, SET and PLAYING
  * close it, INITIAL and FINISHED open it, and a packet the trusted GameController sends that cannot be read closes it
  * and says why (fail safe), while one from elsewhere changes nothing.
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

  /** A packet of the vector's version in `state`, every other field as the vector has it. */
  private def inState(d: GameControlData, state: GameState): Array[Byte] = {
    val moved = d match {
      case v: ControlData2014 => v.copy(gameState = state)
      case v: HlControlData   => v.copy(gameState = state)
      case v: HslControlData  => v.copy(gameState = state)
    }
    GameControllerCodec.encodeControl(moved).fold(e => fail(e.describe), identity)
  }

  private val versions = Seq(
    GameControlVersion.V19 -> vector("v19-playing.bin"),
    GameControlVersion.V12 -> vector("v12-playing.bin"),
    GameControlVersion.V8 -> vector("v8-playing.bin"),
    GameControlVersion.V7 -> vector("v7-playing.bin")
  )

  "A gateway in competition mode" must {
    "close the gate in READY, SET and PLAYING of versions 19, 12, 8 and 7, refusing calls, and open it after" in {
      val f = new GatewayFixture(testKit, "competition.enabled = on\ngame-controller.trusted-sources = [\"127.0.0.1\"]")
      val gc = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      def send(bytes: Array[Byte]): Unit = { gc.send(ByteBuffer.wrap(bytes), f.addresses.gameController.get); () }
      try {
        f.robot(8)
        f.awaitEvent(10.seconds) { case RobotOnline(8, _) => () }
        val connected = f.connect(8)
        // A loaded machine may take the robot offline for a moment while its JVM warms up: it comes back by itself.
        eventually(timeout(20.seconds)) { call(connected, "system.ping").result.isRight shouldBe true }
        versions.foreach { case (version, packet) =>
          Seq(GameState.Ready, GameState.Set, GameState.Playing).foreach { state =>
            send(inState(packet, state))
            f.awaitEvent(10.seconds) { case GameStateUpdated(d) if d.version == version && d.gameState == state => () }
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
          send(inState(packet, GameState.Finished))
          f.awaitEvent(10.seconds) {
            case GameStateUpdated(d) if d.version == version && d.gameState == GameState.Finished => ()
          }
          withClue(s"version ${version.number} FINISHED: ") {
            f.traffic().gateOpen shouldBe true
            eventually(timeout(20.seconds)) { call(connected, "system.ping").result.isRight shouldBe true }
          }
        }
      } finally {
        gc.close()
        f.stop()
      }
    }

    "close the gate on a packet of the trusted GameController it cannot read, say why, and ignore one from elsewhere" in {
      val f = new GatewayFixture(testKit, "competition.enabled = on\ngame-controller.trusted-sources = [\"127.0.0.1\"]")
      val gc = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      val stranger = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.2", 0))
      val target = f.addresses.gameController.get
      // A version yet to come: RGme, version 20, 200 bytes.
      val future = "RGme".getBytes("US-ASCII") ++ Array[Byte](20) ++ new Array[Byte](195)
      try {
        f.robot(9)
        f.awaitEvent(10.seconds) { case RobotOnline(9, _) => () }
        val connected = f.connect(9)
        stranger.send(ByteBuffer.wrap(future), target)
        eventually(timeout(20.seconds)) { call(connected, "system.ping").result.isRight shouldBe true }
        f.traffic().gateOpen shouldBe true

        gc.send(ByteBuffer.wrap(future), target)
        eventually(timeout(10.seconds)) {
          val t = f.traffic()
          t.gateOpen shouldBe false
          t.gateReason shouldBe Some(
            "the trusted GameController's packet cannot be read: RGme packet of unknown version: " +
              "bytes from offset 4 are 14 00 00 00")
        }
        eventually(timeout(10.seconds)) {
          call(connected, "system.ping").result shouldBe Left(RobotFailure.RuleGate(Outbox.NoSendingWhileGameRuns))
        }
        f.stats().rejected.get(Rejection.BadGameControllerPacket.name) shouldBe Some(1L)
        f.stats().rejected.get(Rejection.UntrustedGameController.name) shouldBe Some(1L)

        // A readable INITIAL within the hold does not open it: the GameController may send both kinds each round.
        val initial = inState(vector("v19-initial.bin"), GameState.Initial)
        gc.send(ByteBuffer.wrap(initial), target)
        f.awaitEvent(10.seconds) { case GameStateUpdated(d) if d.gameState == GameState.Initial => () }
        f.traffic().gateOpen shouldBe false
        // Once the unreadable packets stop, the next readable one decides again.
        Thread.sleep(CompetitionGate.UnreadableHoldNanos / 1000000L + 200L)
        gc.send(ByteBuffer.wrap(initial), target)
        eventually(timeout(10.seconds)) { f.traffic().gateOpen shouldBe true }
        eventually(timeout(20.seconds)) { call(connected, "system.ping").result.isRight shouldBe true }
      } finally {
        gc.close()
        stranger.close()
        f.stop()
      }
    }
  }
}
