package naogateway.integration

import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway._
import naogateway.wire.gamecontroller._

/** The message budget and the check for a second GameController in a real gateway, on loopback. */
class TeamMessageBudgetSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  private def v19(state: GameState, packetNumber: Int): Array[Byte] = {
    val d = GameControllerCodec.decodeControl(GameControllerVectors.bytes("v19-initial.bin")) match {
      case Right(d: HslControlData) => d
      case other                    => fail(s"$other")
    }
    GameControllerCodec.encodeControl(d.copy(gameState = state, packetNumber = packetNumber)).fold(e => fail(e.describe), identity)
  }

  private def source(f: GatewayFixture): Gateway.GameSource = {
    val probe = createTestProbe[Gateway.GameSource]()
    f.gateway ! Gateway.GetGameSource(probe.ref)
    probe.receiveMessage(10.seconds)
  }

  "A gateway counting team 12's messages" must {
    "count what it hears on UDP 10000 + team number as the GameController does, and say so with warnings" in {
      // Team 12 plays in the vectors; its port is 10012.
      val f = new GatewayFixture(testKit, "game-controller.trusted-sources = [\"127.0.0.1\"]\ngame-controller.team-messages.team-number = 12")
      val gc = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      val second = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      val robot = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      val team = new InetSocketAddress("127.0.0.1", 10012)
      val gcPort = f.addresses.gameController.get
      try {
        f.settings.teamMessages.port shouldBe 10012
        // INITIAL: heard, not counted.
        gc.send(ByteBuffer.wrap(v19(GameState.Initial, 1)), gcPort)
        f.awaitEvent(10.seconds) { case GameStateUpdated(d) if d.gameState == GameState.Initial => () }
        (1 to 3).foreach(_ => robot.send(ByteBuffer.wrap(new Array[Byte](100)), team))
        eventually(timeout(10.seconds)) { source(f).budget.get should include("12000 of 12000 left, 0 counted") }
        // READY: 5 counted, one of them over 512 bytes.
        gc.send(ByteBuffer.wrap(v19(GameState.Ready, 2)), gcPort)
        f.awaitEvent(10.seconds) { case GameStateUpdated(d) if d.gameState == GameState.Ready => () }
        (1 to 4).foreach(_ => robot.send(ByteBuffer.wrap(new Array[Byte](200)), team))
        robot.send(ByteBuffer.wrap(new Array[Byte](600)), team)
        eventually(timeout(10.seconds)) {
          val s = source(f)
          s.budget.get should include("11995 of 12000 left, 5 counted")
          s.budget.get should include("GameController says 12000")
          s.warnings should contain("1 team message(s) over 512 bytes: the GameController resets the score to 0")
        }
        // A second GameController (same host, another port) with packet numbers that interleave: a warning, and its
        // PLAYING changes nothing.
        (1 to 4).foreach { i =>
          second.send(ByteBuffer.wrap(v19(GameState.Playing, 100 + i)), gcPort)
          gc.send(ByteBuffer.wrap(v19(GameState.Ready, 2 + i)), gcPort)
        }
        eventually(timeout(10.seconds)) {
          source(f).warnings.exists(_.startsWith("2 GameControllers on this field: game state from 127.0.0.1:" +
            gc.getLocalAddress.asInstanceOf[InetSocketAddress].getPort + " only")) shouldBe true
        }
        val game = createTestProbe[Option[GameControlData]]()
        f.gateway ! Gateway.GetGameState(game.ref)
        game.receiveMessage().map(_.gameState) shouldBe Some(GameState.Ready)
        f.traffic().gateReason shouldBe Some("the game is running (Ready)")
      } finally {
        gc.close(); second.close(); robot.close()
        f.stop()
      }
    }
  }
}
