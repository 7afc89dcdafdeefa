package hostile

import java.net.{InetSocketAddress, StandardProtocolFamily, StandardSocketOptions}
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.concurrent.Eventually
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.GatewayAccess
import naogateway.api.{GameSource, GameStateUpdated}
import naogateway.gateway.Rejection
import naogateway.integration.GatewayFixture
import naogateway.testkit.TestLoopback
import naogateway.wire.gamecontroller._

/** The GameController's packets carry no authentication (docs/protocol.md 10.7): a real gateway in competition mode
  * against what a stranger on the field's WiFi can send. The trusted GameController on 127.0.0.1 sends version-20
  * PLAYING twice a second while a second socket bound to the same address and port (SO_REUSEPORT) sends forged INITIAL
  * packets, numbered as the next real ones, in between: the gate stays closed. A flood from another loopback address
  * does not keep the trusted packets from being read. And the gate follows a version-20 game, and a GameController
  * upgraded from version 19 to 20 while running. Loopback only, bounded in packets and time.
  */
class HostileGameControllerSpec
    extends ScalaTestWithActorTestKit
    with AnyWordSpecLike
    with LogCapturing
    with Eventually {

  private val v20: Hsl20ControlData =
    GameControllerCodec.decodeControl(GameControllerVectors.bytes("v20-initial.bin")) match {
      case Right(d: Hsl20ControlData) => d
      case other                      => fail(s"v20-initial.bin: $other")
    }

  private val v19: HslControlData =
    GameControllerCodec.decodeControl(GameControllerVectors.bytes("v19-initial.bin")) match {
      case Right(d: HslControlData) => d
      case other                    => fail(s"v19-initial.bin: $other")
    }

  private def packet20(state: GameState, number: Int): Array[Byte] =
    GameControllerCodec.encodeControl(v20.copy(gameState = state, packetNumber = number & 0xff)).toOption.get

  private def packet19(state: GameState, number: Int): Array[Byte] =
    GameControllerCodec.encodeControl(v19.copy(gameState = state, packetNumber = number & 0xff)).toOption.get

  private def competition(extra: String = "") = GatewayFixtureConfig +
    (if (extra.isEmpty) "" else "\n" + extra)

  private val GatewayFixtureConfig =
    "competition.enabled = on\ngame-controller.trusted-sources = [\"127.0.0.1\"]\ngame-controller.gate-open-after = 1s"

  /** A socket on 127.0.0.1 with SO_REUSEPORT, so a second one can bind the same address and port. */
  private def reusable(port: Int): DatagramChannel = {
    val c = DatagramChannel.open(StandardProtocolFamily.INET)
    if (!c.supportedOptions().contains(StandardSocketOptions.SO_REUSEPORT)) {
      c.close()
      cancel("this platform has no SO_REUSEPORT: the forger cannot share the GameController's port")
    }
    c.setOption[java.lang.Boolean](StandardSocketOptions.SO_REUSEPORT, true)
    c.bind(new InetSocketAddress("127.0.0.1", port))
  }

  private def send(c: DatagramChannel, bytes: Array[Byte], f: GatewayFixture): Unit = {
    c.send(ByteBuffer.wrap(bytes), f.addresses.gameController.get)
    ()
  }

  /** Sends `state` from `c` every 200 ms, numbered from `from`, until the gate opens (at most 40); the next number. */
  private def openWith(f: GatewayFixture, c: DatagramChannel, from: Int,
      packet: (GameState, Int) => Array[Byte] = packet20, state: GameState = GameState.Initial): Int = {
    var n = from
    while (!f.traffic().gateOpen) {
      if (n - from >= 40) fail(s"the gate did not open on $state")
      send(c, packet(state, n), f)
      n += 1
      Thread.sleep(200)
    }
    n
  }

  private def source(f: GatewayFixture): GameSource = {
    val probe = createTestProbe[GameSource]()
    f.gateway ! GatewayAccess.GetGameSource(probe.ref)
    probe.receiveMessage(10.seconds)
  }

  "A gateway in competition mode" must {
    "keep the gate closed while forged INITIAL packets from the GameController's own address and port come between " +
      "its real PLAYING ones" in {
        val f = new GatewayFixture(testKit, competition())
        val gc = reusable(0)
        val forger = reusable(gc.getLocalAddress.asInstanceOf[InetSocketAddress].getPort)
        try {
          gc.getLocalAddress shouldBe forger.getLocalAddress
          var n = openWith(f, gc, 1)
          f.traffic().gateOpen shouldBe true
          // Kick-off: the real GameController says PLAYING every 500 ms; the forger says INITIAL 250 ms after each,
          // with the number the next real packet will have.
          send(gc, packet20(GameState.Playing, n), f)
          n += 1
          eventually(timeout(10.seconds)) { f.traffic().gateOpen shouldBe false }
          val seen = (1 to 12).flatMap { _ =>
            Thread.sleep(250)
            send(forger, packet20(GameState.Initial, n), f)
            Thread.sleep(250)
            val afterForged = f.traffic().gateOpen
            send(gc, packet20(GameState.Playing, n), f)
            n += 1
            Seq(afterForged, f.traffic().gateOpen)
          }
          all(seen) shouldBe false
          f.traffic().gateReason.getOrElse("") should (startWith("the game is running") or startWith("opening once"))
          eventually(timeout(10.seconds)) {
            source(f).warnings.exists(w =>
              w.startsWith("competition gate: ") && w.contains("contradiction(s) while it waited to open")) shouldBe
              true
          }
          // The forger stops; the real GameController ends the half: the gate opens after a while of FINISHED.
          openWith(f, gc, n, state = GameState.Finished)
          f.traffic().gateOpen shouldBe true
        } finally {
          forger.close()
          gc.close()
          f.stop()
        }
      }

    "read the trusted GameController's packets while a stranger floods the port past its rate cap" in {
      val f = new GatewayFixture(testKit, competition("game-controller.max-datagrams-per-second = 100"))
      val gc = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      val stranger = DatagramChannel.open().bind(new InetSocketAddress(TestLoopback.address(0), 0))
      try {
        val before = f.stats().gameControllerPackets
        val junk = packet20(GameState.Initial, 1)
        // 10 trusted packets, each among 300 of the stranger's: 3000 a burst, 30 times the cap.
        (1 to 10).foreach { i =>
          (1 to 300).foreach { k =>
            stranger.send(ByteBuffer.wrap(junk), f.addresses.gameController.get)
            if (k == 150) send(gc, packet20(GameState.Ready, i), f)
          }
          Thread.sleep(20)
        }
        eventually(timeout(10.seconds)) { f.stats().gameControllerPackets - before shouldBe 10L }
        // The flood did go over the cap: once its second is over, the next datagram brings the count of the dropped.
        Thread.sleep(1100)
        stranger.send(ByteBuffer.wrap(junk), f.addresses.gameController.get)
        eventually(timeout(10.seconds)) {
          f.stats().rejected.getOrElse(Rejection.GatewayBusy.name, 0L) should be > 1000L
        }
        f.traffic().gateReason shouldBe Some("the game is running (Ready)")
      } finally {
        stranger.close()
        gc.close()
        f.stop()
      }
    }

    "close the gate in READY, SET and PLAYING of version 20 and open it after a while of INITIAL or FINISHED; keep " +
      "it right when the GameController is upgraded from version 19 to 20 while the game runs" in {
        val f = new GatewayFixture(testKit, competition())
        val gc = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
        try {
          var n = openWith(f, gc, 1)
          Seq(GameState.Initial, GameState.Finished).foreach { opening =>
            Seq(GameState.Ready, GameState.Set, GameState.Playing).foreach { state =>
              send(gc, packet20(state, n), f)
              n += 1
              f.awaitEvent(10.seconds) {
                case GameStateUpdated(d) if d.version == GameControlVersion.V20 && d.gameState == state => ()
              }
              withClue(s"version 20 $state: ") {
                f.traffic().gateOpen shouldBe false
                f.traffic().gateReason shouldBe Some(s"the game is running ($state)")
              }
            }
            send(gc, packet20(opening, n), f)
            n += 1
            f.awaitEvent(10.seconds) { case GameStateUpdated(d) if d.gameState == opening => () }
            f.traffic().gateOpen shouldBe false
            n = openWith(f, gc, n, state = opening)
          }

          // Version 19 runs a game; between two packets the GameController is replaced by version 20, counting from 1.
          send(gc, packet19(GameState.Playing, 200), f)
          f.awaitEvent(10.seconds) {
            case GameStateUpdated(d) if d.version == GameControlVersion.V19 && d.gameState == GameState.Playing => ()
          }
          f.traffic().gateOpen shouldBe false
          send(gc, packet20(GameState.Set, 1), f)
          f.awaitEvent(10.seconds) {
            case GameStateUpdated(d) if d.version == GameControlVersion.V20 && d.gameState == GameState.Set => ()
          }
          f.traffic().gateReason shouldBe Some("the game is running (Set)")
          // A version-19 FINISHED from before the switch, late, opens nothing; the new GameController's do, in time.
          send(gc, packet19(GameState.Finished, 201), f)
          send(gc, packet20(GameState.Playing, 2), f)
          f.awaitEvent(10.seconds) {
            case GameStateUpdated(d) if d.version == GameControlVersion.V20 && d.gameState == GameState.Playing => ()
          }
          f.traffic().gateOpen shouldBe false
          openWith(f, gc, 3, state = GameState.Finished)
          val game = createTestProbe[Option[GameControlData]]()
          f.gateway ! GatewayAccess.GetGameState(game.ref)
          game.receiveMessage().map(_.version) shouldBe Some(GameControlVersion.V20)
        } finally {
          gc.close()
          f.stop()
        }
      }
  }
}
