package naogateway.integration

import java.net.{InetAddress, InetSocketAddress}
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import com.typesafe.config.ConfigFactory
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.GatewayAccess
import naogateway.api.{GameSource, GameStateUpdated}
import naogateway.gateway.GatewaySettings
import naogateway.wire.gamecontroller._

/** The monitor role against a stand-in version-19 GameController on loopback: the gateway's `RGTr` requests, kept
  * alive; the true state (`RGTD`) taken over the broadcast one for the gate and the view; the forwarded status messages
  * on their port shown; and a configuration that would make this host send status messages refused.
  */
class MonitorRoleSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  private val initial: HslControlData =
    GameControllerCodec.decodeControl(GameControllerVectors.bytes("v19-initial.bin")) match {
      case Right(d: HslControlData) => d
      case other                    => fail(s"$other")
    }
  private def broadcast(state: GameState): Array[Byte] =
    GameControllerCodec.encodeControl(initial.copy(gameState = state)).fold(e => fail(e.describe), identity)
  private def trueData(state: GameState): Array[Byte] =
    GameControllerCodec.encodeTrueData(initial.copy(gameState = state)).fold(e => fail(e.describe), identity)

  private def freeUdpPort(): Int = {
    val c = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
    try c.getLocalAddress.asInstanceOf[InetSocketAddress].getPort
    finally c.close()
  }

  private def source(f: GatewayFixture): GameSource = {
    val probe = createTestProbe[GameSource]()
    f.gateway ! GatewayAccess.GetGameSource(probe.ref)
    probe.receiveMessage(10.seconds)
  }

  "A gateway in the monitor role" must {
    "register with RGTr and keep registering, prefer RGTD to RGme, and show the forwarded robot statuses" in {
      val standIn = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      val stranger = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.2", 0))
      val requestPort = standIn.getLocalAddress.asInstanceOf[InetSocketAddress].getPort
      val statusPort = freeUdpPort()
      val f = new GatewayFixture(
        testKit,
        s"""competition.enabled = on
           |game-controller.trusted-sources = ["127.0.0.1"]
           |game-controller.monitor { enabled = on, address = "127.0.0.1", request-port = $requestPort, status-port = $statusPort,
           |  request-interval = 300ms, true-state-fresh = 2s }""".stripMargin
      )
      val gcPort = f.addresses.gameController.get
      try {
        // The requests: RGTr and version 0, from the gateway's GameController socket, again and again.
        standIn.configureBlocking(true)
        standIn.socket.setSoTimeout(10000)
        val requests = (1 to 3).map { _ =>
          val buffer = ByteBuffer.allocate(64)
          val from = standIn.receive(buffer).asInstanceOf[InetSocketAddress]
          buffer.flip()
          val bytes = new Array[Byte](buffer.remaining); buffer.get(bytes)
          from -> bytes.toVector
        }
        all(requests.map(_._2)) shouldBe ("RGTr".getBytes("US-ASCII") :+ 0.toByte).toVector
        all(requests.map(_._1.getPort)) shouldBe gcPort.getPort

        // The broadcast state counts until a true state arrives; then the true one rules while it is fresh.
        standIn.send(ByteBuffer.wrap(broadcast(GameState.Playing)), gcPort)
        f.awaitEvent(10.seconds) { case GameStateUpdated(d) if d.gameState == GameState.Playing => () }
        standIn.send(ByteBuffer.wrap(trueData(GameState.Ready)), gcPort)
        f.awaitEvent(10.seconds) { case GameStateUpdated(d) if d.gameState == GameState.Ready => () }
        (1 to 3).foreach(_ => standIn.send(ByteBuffer.wrap(broadcast(GameState.Playing)), gcPort))
        standIn.send(ByteBuffer.wrap(trueData(GameState.Ready)), gcPort)
        eventually(timeout(10.seconds)) { source(f).trueStateAgeMillis.exists(_ < 2000) shouldBe true }
        val game = createTestProbe[Option[GameControlData]]()
        f.gateway ! GatewayAccess.GetGameState(game.ref)
        game.receiveMessage().map(_.gameState) shouldBe Some(GameState.Ready)
        f.traffic().gateReason shouldBe Some("the game is running (Ready)")

        // Forwarded status messages: the robot's address, then its RGrt version 4. Only from the GameController.
        val status = ReturnStatus(3, 12, fallen = true, (1000f, -500f, 1.5f), 2f, (250f, -100f))
        val forwarded =
          InetAddress.getByName("10.0.0.23").getAddress ++ GameControllerCodec.encodeStatus(status).toOption.get
        val statusAt = new InetSocketAddress("127.0.0.1", statusPort)
        stranger.send(ByteBuffer.wrap(InetAddress.getByName("10.0.0.99").getAddress ++
            GameControllerCodec.encodeStatus(status.copy(player = 4)).toOption.get), statusAt)
        standIn.send(ByteBuffer.wrap(forwarded), statusAt)
        eventually(timeout(10.seconds)) {
          source(f).forwarded.map(s => s.from.getHostAddress -> s.status) shouldBe Vector("10.0.0.23" -> status)
        }
      } finally {
        standIn.close(); stranger.close()
        f.stop()
      }
    }

    "be refused, with a clear error, when a configured robot would send status messages from this host" in {
      val config = ConfigFactory.parseString(
        """game-controller.monitor { enabled = on, address = "10.0.0.5" }
          |robots = [{ id = 1, address = "127.0.0.1" }]""".stripMargin)
        .withFallback(ConfigFactory.load().getConfig("naogateway"))
      val refused = intercept[IllegalArgumentException](GatewaySettings.fromConfig(config))
      refused.getMessage should include("robot 1 at 127.0.0.1 runs on this host")
      refused.getMessage should include("refuse this host as a monitor")
      val noAddress = ConfigFactory.parseString("game-controller.monitor.enabled = on").withFallback(
        ConfigFactory.load().getConfig("naogateway"))
      intercept[IllegalArgumentException](GatewaySettings.fromConfig(noAddress)).getMessage should include(
        "game-controller.monitor.address")
      GatewaySettings.fromConfig(ConfigFactory.load().getConfig("naogateway")).monitor shouldBe None
    }
  }
}
