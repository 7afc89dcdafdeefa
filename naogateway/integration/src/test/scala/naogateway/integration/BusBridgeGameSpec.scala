package naogateway.integration

import java.net.{InetSocketAddress, ServerSocket, Socket, SocketTimeoutException}

import scala.concurrent.duration._
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway._
import naogateway.sim._
import naogateway.testkit.TestLoopback
import naogateway.wire.Dynamixel
import naogateway.gateway.BusBridgeServer
import naogateway.gateway.BusBridgeSettings
import naogateway.api.RobotOnline

/** The bus bridge during the demo's game (docs/protocol.md 6.9, README "Calibrating a HaViMo2 over WiFi"): competition
  * mode off, as in the demo, and the simulated GameController sending each round to the gateway and to the robot, as
  * the launcher wires it. The bridge answers before the game, its client is closed when the game starts (READY) and no
  * connection is taken while it runs, and it answers again once the game has not run for `gate-open-after`; the robot
  * hears the same packets.
  */
class BusBridgeGameSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {

  private val robotId = 2

  /** A client of the bridge at `port` whose ping of servo 1 is answered, tried until `within` has passed. */
  private def answering(port: Int, within: FiniteDuration): Option[Socket] = {
    val deadline = within.fromNow
    var found = Option.empty[Socket]
    while (found.isEmpty && deadline.hasTimeLeft()) {
      Try(new Socket("127.0.0.1", port)).toOption.foreach { s =>
        s.setSoTimeout(2000)
        s.getOutputStream.write(Dynamixel.packet(1, Dynamixel.Ping, Nil))
        if (Try(s.getInputStream.readNBytes(6).toVector).toOption.contains(Dynamixel.packet(1, 0, Nil).toVector))
          found = Some(s)
        else s.close()
      }
      if (found.isEmpty) Thread.sleep(200)
    }
    found
  }

  "the bus bridge in the demo's game" must {
    "answer before the game, close when the game starts, refuse while it runs and answer again after it" in {
      val f = new GatewayFixture(testKit,
        BusBridgeSpec.Patient + "\ngame-controller.trusted-sources = [\"127.0.0.1\"]\n" +
          "game-controller.gate-open-after = 1s")
      val base = {
        val s = new ServerSocket(0, 1, java.net.InetAddress.getLoopbackAddress)
        try s.getLocalPort - robotId
        finally s.close()
      }
      val bridge = spawn(BusBridgeServer(f.gateway, BusBridgeSettings(enabled = true, basePort = base), None))
      val started = createTestProbe[SimulatedRobot.StartResult]()
      spawn(SimulatedRobot(
          SimulatedRobotSettings(FirmwareSettings(robotId), f.addresses.robots,
            bindAddress = new InetSocketAddress(TestLoopback.address(), 0), faithfulLink = false)
            .withStream(f.settings.stream),
          Some(started.ref)
        ))
      val (robot, robotAddress) = started.receiveMessage(10.seconds) match {
        case SimulatedRobot.Started(_, ref, address) => ref -> address
        case other                                   => fail(s"robot did not start: $other")
      }
      try {
        f.awaitEvent(20.seconds) { case RobotOnline(`robotId`, _) => () }
        // Before the game (no GameController yet): the bridge answers.
        val before = answering(base + robotId, 30.seconds).getOrElse(fail("the bridge never answered before the game"))
        before.setSoTimeout(20000)
        // The game: INITIAL for 1 s, then READY, SET and PLAYING, then FINISHED for long, to the gateway and the robot.
        val gc = spawn(SimulatedGameController(SimulatedGameControllerSettings(
              f.addresses.gameController.get,
              initial = 1.second,
              ready = 2.seconds,
              set = 1.second,
              playing = 3.seconds,
              finished = 60.seconds,
              interval = 100.millis,
              robots = Vector(robotAddress)
            )))
        try {
          // READY: the gateway closes the bridge's client.
          val read = Try(before.getInputStream.read()).fold({ case _: SocketTimeoutException => 0; case _ => -1 },
            identity)
          read shouldBe -1
          before.close()
          val runningAt = System.nanoTime()
          // While the game runs nothing listens; the robot heard the GameController as the gateway did.
          val unbound = 5.seconds.fromNow
          while (Try(new Socket("127.0.0.1", base + robotId).close()).isSuccess && unbound.hasTimeLeft())
            Thread.sleep(100)
          Try(new Socket("127.0.0.1", base + robotId)).isFailure shouldBe true
          val view = createTestProbe[RobotView]()
          robot ! SimulatedRobot.GetState(view.ref)
          view.receiveMessage(10.seconds).firmware.gameControllerPackets should be > 0L
          // After PLAYING (6 s from the start) and the gate's second of FINISHED: the bridge answers again.
          val after = answering(base + robotId, 40.seconds).getOrElse(fail("the bridge never answered after the game"))
          // Not before the game ended: READY to the end of PLAYING is 6 s, and the gate waits 1 s more.
          (System.nanoTime() - runningAt).nanos should be > 3.seconds
          after.close()
        } finally testKit.stop(gc)
      } finally {
        testKit.stop(bridge)
        f.stop()
      }
    }
  }
}
