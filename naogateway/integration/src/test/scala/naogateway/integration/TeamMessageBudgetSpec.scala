package naogateway.integration

import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.GatewayAccess
import naogateway.api.{GameSource, GameStateUpdated}
import naogateway.gateway.Rejection
import naogateway.wire.gamecontroller._

/** The message budget and the check for a second GameController in a real gateway, on loopback. */
class TeamMessageBudgetSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  private def v19(state: GameState, packetNumber: Int): Array[Byte] = {
    val d = GameControllerCodec.decodeControl(GameControllerVectors.bytes("v19-initial.bin")) match {
      case Right(d: HslControlData) => d
      case other                    => fail(s"$other")
    }
    GameControllerCodec.encodeControl(d.copy(gameState = state, packetNumber = packetNumber)).fold(
      e => fail(e.describe), identity)
  }

  private def source(f: GatewayFixture): GameSource = {
    val probe = createTestProbe[GameSource]()
    f.gateway ! GatewayAccess.GetGameSource(probe.ref)
    probe.receiveMessage(10.seconds)
  }

  "A gateway counting team 12's messages" must {

    "hand the gateway at most the cap a second from a flood on the GameController and team ports, counting the rest" in {
      val f = new GatewayFixture(
        testKit,
        "game-controller.trusted-sources = [\"127.0.0.1\"]\n" +
          "game-controller.team-messages.team-number = 12\ngame-controller.max-datagrams-per-second = 50\n" +
          "game-controller.team-messages.max-datagrams-per-second = 50"
      )
      val flood = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      val gc = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      val gcPort = f.addresses.gameController.get
      val team = new InetSocketAddress("127.0.0.1", 10012)
      try {
        gc.send(ByteBuffer.wrap(v19(GameState.Ready, 1)), gcPort)
        f.awaitEvent(10.seconds) { case GameStateUpdated(d) if d.gameState == GameState.Ready => () }
        val junk = Array.fill[Byte](40)(7)
        (1 to 3000).foreach { _ =>
          flood.send(ByteBuffer.wrap(junk), gcPort)
          flood.send(ByteBuffer.wrap(junk), team)
        }
        // The second after the flood: one more datagram on each port brings the count of what was dropped.
        Thread.sleep(1200)
        gc.send(ByteBuffer.wrap(v19(GameState.Ready, 2)), gcPort)
        flood.send(ByteBuffer.wrap(junk), team)
        eventually(timeout(10.seconds)) {
          val rejected = f.stats().rejected
          rejected.getOrElse(Rejection.GatewayBusy.name, 0L) should be > 0L
          /* What passed the cap was read and refused as it always is: at most the cap for each second the flood
           * spanned. */
          rejected.getOrElse(Rejection.BadGameControllerPacket.name, 0L) should be <= 150L
        }
        // The team's budget counted only what passed the cap; the game still follows the trusted GameController.
        val counted = "(\\d+) counted".r.findFirstMatchIn(source(f).budget.get).map(_.group(1).toInt)
        counted.get should be <= 151
        f.traffic().gateReason shouldBe Some("the game is running (Ready)")
      } finally {
        flood.close(); gc.close()
        f.stop()
      }
    }
    "count what it hears on UDP 10000 + team number as the GameController does, and say so with warnings" in {
      // Team 12 plays in the vectors; its port is 10012.
      val f = new GatewayFixture(testKit,
        "game-controller.trusted-sources = [\"127.0.0.1\"]\ngame-controller.team-messages.team-number = 12")
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
        f.gateway ! GatewayAccess.GetGameState(game.ref)
        game.receiveMessage().map(_.gameState) shouldBe Some(GameState.Ready)
        f.traffic().gateReason shouldBe Some("the game is running (Ready)")
      } finally {
        gc.close(); second.close(); robot.close()
        f.stop()
      }
    }
  }
}
