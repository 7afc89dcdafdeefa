package naogateway.integration

import java.net.{InetAddress, InetSocketAddress}

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{ActorTestKit, TestProbe}
import akka.actor.typed.ActorRef
import com.typesafe.config.ConfigFactory

import naogateway.access.{GatewayAccess, RobotAccess}
import naogateway.api.{GatewayAddresses, GatewayEvent, GatewayStats, TrafficStats}
import naogateway.gateway.{Gateway, GatewaySettings}
import naogateway.gateway.robot.{RobotActor, RobotEffects, RobotTestHooks}
import naogateway.sim.{FirmwareSettings, SimulatedRobot, SimulatedRobotSettings}
import naogateway.testkit.TestLoopback

/** A gateway on loopback ports chosen by the system, and simulated robots pointed at it; public API only. Call `stop()`
  * at the end of each test: a fixture left running (robots streaming to their gateway) loads the next.
  */
final class GatewayFixture(testKit: ActorTestKit, overrides: String = "") {
  private val config = ConfigFactory
    .parseString(s"""
      |link.bind-address = "127.0.0.1"
      |link.robot-port = 0
      |game-controller.bind-address = "127.0.0.1"
      |game-controller.port = 0
      |$overrides
      |""".stripMargin)
    .withFallback(ConfigFactory.load().getConfig("naogateway"))

  val settings: GatewaySettings = GatewaySettings.fromConfig(config)
  val gateway: ActorRef[GatewayAccess.Command] = testKit.spawn(Gateway(settings))
  val addresses: GatewayAddresses = {
    val probe = testKit.createTestProbe[GatewayAddresses]()
    gateway ! GatewayAccess.GetAddresses(probe.ref)
    probe.receiveMessage(10.seconds)
  }
  val events: TestProbe[GatewayEvent] = testKit.createTestProbe[GatewayEvent]()
  gateway ! GatewayAccess.Subscribe(events.ref)
  private var robots = Vector.empty[ActorRef[SimulatedRobot.Command]]

  /** Starts robot `robotId` on a loopback address of its own (`at`), sending to `to` (the gateway unless a proxy is
    * given); it receives on `at`:3838, where the gateway must send. Returns the robot and its receive address.
    */
  def robot(robotId: Int, to: InetSocketAddress = addresses.robots, faithful: Boolean = false,
      firmware: FirmwareSettings => FirmwareSettings = identity,
      at: InetAddress = TestLoopback.address()): (ActorRef[SimulatedRobot.Command], InetSocketAddress) = {
    val started = testKit.createTestProbe[SimulatedRobot.StartResult]()
    testKit.spawn(
      SimulatedRobot(SimulatedRobotSettings(firmware(FirmwareSettings(robotId)), to,
          bindAddress = new InetSocketAddress(at, 0),
          faithfulLink = faithful), Some(started.ref)),
      s"sim-robot-$robotId-${System.nanoTime()}"
    )
    started.receiveMessage(10.seconds) match {
      case SimulatedRobot.Started(_, ref, address) =>
        robots :+= ref
        ref -> address
      case other => throw new IllegalStateException(s"robot $robotId did not start: $other")
    }
  }

  /** Waits for an event matching `pf`, skipping others (status updates arrive five times a second per robot). */
  def awaitEvent[T](within: FiniteDuration)(pf: PartialFunction[GatewayEvent, T]): T = {
    val deadline = within.fromNow
    var found: Option[T] = None
    while (found.isEmpty) {
      val e = events.receiveMessage(deadline.timeLeft.max(1.milli))
      found = pf.lift(e)
    }
    found.get
  }

  def robotActor(robotId: Int): ActorRef[RobotActor.Command] =
    GatewayInternals.robotActor(gateway, robotId)(testKit.system)
      .getOrElse(throw new NoSuchElementException(s"robot $robotId unknown"))

  def connect(robotId: Int): RobotEffects.Connected =
    GatewayInternals.connect(gateway, robotId)(testKit.system)
      .getOrElse(throw new NoSuchElementException(s"robot $robotId unknown"))

  /** Makes robot `robotId`'s vision actor fail as a bug would, for restart specs outside the package. */
  def crashVision(robotId: Int): Unit = RobotTestHooks.crashVision(connect(robotId))

  /** Makes robot `robotId`'s stream actor fail as a bug would. */
  def crashStream(robotId: Int): Unit = RobotTestHooks.crashStream(connect(robotId))

  /** Makes robot `robotId`'s sender fail as a bug would, on its next transmission. */
  def crashSender(robotId: Int): Unit = RobotTestHooks.crashSender(connect(robotId))

  /** Robot `robotId` as the middleware reaches it (its public protocol). */
  def robotAccess(robotId: Int): ActorRef[RobotAccess.Command] = {
    val probe = testKit.createTestProbe[Option[ActorRef[RobotAccess.Command]]]()
    gateway ! GatewayAccess.GetRobotAccess(robotId, probe.ref)
    probe.receiveMessage(10.seconds).getOrElse(throw new NoSuchElementException(s"robot $robotId unknown"))
  }

  /** Robot `robotId`, reachable, as the middleware uses it (its public protocol). */
  def open(robotId: Int): RobotAccess.Opened = {
    val probe = testKit.createTestProbe[RobotAccess.Opened]()
    robotAccess(robotId) ! RobotAccess.Open(probe.ref)
    probe.receiveMessage(10.seconds)
  }

  def stats(): GatewayStats = {
    val probe = testKit.createTestProbe[GatewayStats]()
    gateway ! GatewayAccess.GetStats(probe.ref)
    probe.receiveMessage()
  }

  /** The outbox's traffic figures, asked through the gateway. */
  def traffic(): TrafficStats = {
    val probe = testKit.createTestProbe[TrafficStats]()
    gateway ! GatewayAccess.GetTraffic(probe.ref)
    probe.receiveMessage(10.seconds)
  }

  /** In competition mode: sends version-20 packets in `state` (INITIAL unless said) from `gc`, numbered one after the
    * other from `firstNumber`, every 200 ms, until the gate opens (docs/protocol.md 10.7: it opens only after
    * `gate-open-after` of such packets); at most 60 packets (12 s). Returns the next packet number.
    */
  def openGate(gc: java.nio.channels.DatagramChannel, firstNumber: Int = 1,
      state: naogateway.wire.gamecontroller.GameState = naogateway.wire.gamecontroller.GameState.Initial): Int = {
    import naogateway.wire.gamecontroller._
    val base = GameControllerCodec.decodeControl(GameControllerVectors.bytes("v20-initial.bin")) match {
      case Right(d: Hsl20ControlData) => d.copy(gameState = state)
      case other                      => throw new IllegalStateException(s"v20-initial.bin: $other")
    }
    var n = firstNumber
    while (!traffic().gateOpen) {
      if (n - firstNumber >= 60) throw new IllegalStateException(s"the gate did not open after 60 packets in $state")
      val bytes = GameControllerCodec.encodeControl(base.copy(packetNumber = n & 0xff)).toOption.get
      gc.send(java.nio.ByteBuffer.wrap(bytes), addresses.gameController.get)
      n += 1
      Thread.sleep(200)
    }
    n
  }

  /** Stops every robot started here, then the gateway; returns once all of them have terminated. */
  def stop(): Unit = {
    val watcher = testKit.createTestProbe[Any]()
    robots.foreach(_ ! SimulatedRobot.Stop(testKit.system.ignoreRef))
    // A robot terminates once its socket is closed (or its own stop timeout has passed); one that stopped on its own
    // counts as terminated at once.
    robots.foreach(watcher.expectTerminated(_, 15.seconds))
    robots = Vector.empty
    testKit.stop(gateway, 15.seconds)
  }

  def view(robot: ActorRef[SimulatedRobot.Command]): naogateway.sim.RobotView = {
    val probe = testKit.createTestProbe[naogateway.sim.RobotView]()
    robot ! SimulatedRobot.GetState(probe.ref)
    probe.receiveMessage()
  }
}
