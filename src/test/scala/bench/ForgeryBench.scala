package bench

import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel
import java.util.concurrent.ConcurrentLinkedQueue

import scala.collection.immutable.ListMap
import scala.concurrent.Await
import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.util.Random

import akka.actor.typed.scaladsl.AskPattern._
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, ActorSystem, Scheduler}
import akka.util.Timeout
import com.typesafe.config.ConfigFactory

import naogateway.access.{GatewayAccess, RobotAccess}
import naogateway.api.{CallResult, GatewayEvent, RobotEvent, RobotSnapshot}
import naogateway.gateway.{Gateway, GatewaySettings}
import naogateway.testkit.RelayCapture
import naogateway.sim.network.ForgedFrames
import naogateway.sim.{FirmwareSettings, RobotView, SimulatedRobot, SimulatedRobotSettings}
import naogateway.testkit.TestLoopback
import naogateway.wire._

/** Forged frames against a robot that must sign (docs/protocol.md 6.7), sent from that robot's own IP address at the
  * gateway's robot port: made-up keep-alives claiming an empty battery and a new session (unsigned and signed with
  * another key), replays of the robot's real frames (recorded through the FU-Remote relay), the same with a bit
  * flipped, with a field after the signature and with a broken signature, [[Rounds]] times over; and made-up
  * `motion.posture("stand")` requests (unsigned, and signed with another key) at the robot's receive port.
  *
  *   - `forged_state_changes`: robot state changes they caused: events of the robot that no real keep-alive of it would
  *     cause (`ForgedFrames.stateChanges`: another battery, session, posture, team or role, a restart, a change of
  *     liveness), which is what every subscriber of the gateway, the middleware's safety checks included, sees; plus 1
  *     if the simulated robot's posture changed. Goal 0.
  *   - `forged_datagrams`: forged datagrams sent; `forged_refused`: those the gateway and the robot refused (counted by
  *     kind), which should be all of them.
  */
object ForgeryBench extends Benchmark {
  val name = "forgery"

  /** Batches of forged frames sent. */
  val Rounds: Int = 5

  private val TeamKey =
    SigningKey.fromHex("000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f").toOption.get
  private val WrongKey =
    SigningKey.fromHex("ff0102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f").toOption.get
  private val RobotId = 41

  def run(): ListMap[String, Double] = {
    val ip = TestLoopback.address()
    val recorder = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
    val outsider = DatagramChannel.open().bind(new InetSocketAddress(ip, 0))
    val config = ConfigFactory.load(ConfigFactory.parseString(
        s"""naogateway.link.bind-address = "127.0.0.1"
         |naogateway.link.robot-port = 0
         |naogateway.game-controller.enabled = off
         |naogateway.robots = [ { id = $RobotId, address = "${ip.getHostAddress}", signing = required } ]
         |naogateway.signing.key = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f"
         |naogateway.fu-remote-relay { enabled = on, address = "127.0.0.1", port = ${recorder.getLocalAddress.asInstanceOf[
          InetSocketAddress].getPort} }
         |akka.loglevel = "WARNING"
         |""".stripMargin))
    val system = ActorSystem(Gateway(GatewaySettings.fromConfig(config.getConfig("naogateway"))), "forgery", config)
    implicit val scheduler: Scheduler = system.scheduler
    implicit val timeout: Timeout = Timeout(30.seconds)
    try {
      val events = new ConcurrentLinkedQueue[GatewayEvent]()
      val sink = system.systemActorOf(Behaviors.receiveMessage[GatewayEvent] {
          case e: RobotEvent if e.robotId == RobotId =>
            events.add(e)
            Behaviors.same
          case _ => Behaviors.same
        }, "forgery-events")
      system ! GatewayAccess.Subscribe(sink)
      val addresses = Await.result(system.ask(GatewayAccess.GetAddresses(_)), 30.seconds)
      val robot = system.systemActorOf(
        SimulatedRobot(SimulatedRobotSettings(FirmwareSettings(RobotId, signingKey = Some(TeamKey)),
            addresses.robots, bindAddress = new InetSocketAddress(ip, 0))),
        "forgery-robot"
      )
      def view(): RobotView = Await.result(robot.ask[RobotView](SimulatedRobot.GetState(_)), 30.seconds)
      val actor = Await
        .result(system.ask[Option[ActorRef[RobotAccess.Command]]](GatewayAccess.GetRobotAccess(RobotId, _)), 30.seconds)
        .get
      def snapshot(): RobotSnapshot = Await.result(actor.ask[RobotSnapshot](RobotAccess.GetSnapshot(_)), 30.seconds)
      val connected = Await.result(actor.ask[RobotAccess.Opened](RobotAccess.Open(_)), 30.seconds)
      val ping =
        Await.result(connected.response.ask[CallResult](RobotAccess.Call(RpcCall("system", "ping", Vector.empty), _)),
          30.seconds)
      require(ping.result.isRight, s"the signing robot did not answer: $ping")
      val recorded = RelayCapture.frames(recorder, RobotId, 2.seconds)
      require(recorded.size >= 3, s"only ${recorded.size} frames recorded")
      val truth = snapshot()
      val robotBefore = view()
      val refusedBefore = Await.result(system.ask(GatewayAccess.GetStats(_)), 30.seconds).rejected.values.sum
      events.clear()
      val random = new Random(11)
      val stand = MessageContents(RobotId,
        rpcRequest = Some(RpcCall("motion", "posture", Vector(RpcValue.Text("stand")), Some(9L)).toProto))
      val toRobot = (1 to 100).flatMap(i =>
        Vector(
          ForgedFrames.unsigned(stand),
          FrameSigning.signFrame(stand, HeaderForm.Legacy, WrongKey.robotKey(RobotId), SignedLink.ToRobot(RobotId, 1),
            Long.MaxValue - i)
            .toOption.get
        ))
      val toGateway = (1 to Rounds).flatMap(_ => ForgedFrames.batch(RobotId, recorded, WrongKey, perKind = 200, random))
      // Paced a little, so the kernel's buffers, not the test, decide nothing.
      toGateway.grouped(20).foreach { group =>
        group.foreach(frame => outsider.send(ByteBuffer.wrap(frame), addresses.robots))
        Thread.sleep(1)
      }
      toRobot.grouped(10).foreach { group =>
        group.foreach(frame => outsider.send(ByteBuffer.wrap(frame), robotBefore.address))
        Thread.sleep(2)
      }
      Thread.sleep(2000)
      val seen = events.asScala.toVector
      require(seen.nonEmpty, "no event of the robot while forging: its real keep-alives should have gone on")
      val robotAfter = view()
      val changes = ForgedFrames.stateChanges(seen, truth) + (if (robotAfter.posture != robotBefore.posture) 1 else 0)
      val refusedByGateway =
        Await.result(system.ask(GatewayAccess.GetStats(_)), 30.seconds).rejected.values.sum - refusedBefore
      val refusedByRobot =
        robotAfter.firmware.refusedSignatures.values.sum - robotBefore.firmware.refusedSignatures.values.sum
      println(
        s"  forgery: ${toGateway.size} frames at the gateway, ${toRobot.size} at the robot; refused ${refusedByGateway} and " +
          s"$refusedByRobot; ${seen.size} events of the robot meanwhile, $changes of them forged")
      ListMap(
        "forged_state_changes" -> changes.toDouble,
        "forged_datagrams" -> (toGateway.size + toRobot.size).toDouble,
        "forged_refused" -> (refusedByGateway + refusedByRobot).toDouble
      )
    } finally {
      system.terminate()
      Await.result(system.whenTerminated, 60.seconds)
      recorder.close()
      outsider.close()
    }
  }
}
