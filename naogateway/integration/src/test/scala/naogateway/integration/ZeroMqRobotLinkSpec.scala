package naogateway.integration

import java.net.{InetSocketAddress, Socket}

import scala.concurrent.Await
import scala.concurrent.duration._

import akka.actor.testkit.typed.FishingOutcome
import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit, TestProbe}
import com.typesafe.config.ConfigFactory
import org.scalatest.wordspec.AnyWordSpecLike
import org.zeromq.{SocketType, ZContext}

import naogateway.access.{GatewayAccess, RobotAccess}
import naogateway.api.{
  CallResult,
  GatewayEvent,
  RobotFailure,
  RobotOffline,
  RobotOnline,
  RobotRestarted,
  RobotStatusUpdated
}
import naogateway.gateway.{Gateway, GatewaySettings}
import naogateway.gateway.robot.{CallId, Outbox, RobotEffects}
import naogateway.sim.{FirmwareSettings, ZeroMqSimulatedRobot}
import naogateway.wire.{MessageContents, Posture, RpcCall, RpcReply, RpcValue}
import naogateway.gateway.link.ZeroMqRobotLink
import naogateway.transport.ZeroMqLoop
import naogateway.gateway.robot.NoResponseActor
import naogateway.api.Priority
import naogateway.gateway.robot.RobotFrames

object ZeroMqRobotLinkSpec {

  /** Every endpoint a test binds lets the system pick the port; the real one is read back after binding. */
  val AnyPort: String = "tcp://127.0.0.1:*"

  // A posture motion holds the REP socket for 1.5 s, so probes sent meanwhile are answered only afterwards. Probing
  // starts 600 ms into the silence, and three 1 s probe timeouts leave about 2 s beyond the motion's end before the
  // robot would count as lost.
  val config: String =
    """naogateway {
       |  link { bind-address = "127.0.0.1", robot-port = 0 }
       |  game-controller.enabled = off
       |  zeromq {
       |    status-interval = 100ms
       |    status-timeout = 2s
       |    heartbeat { quiet-after = 600ms, probe-timeout = 1s, chances = 3 }
       |  }
       |}
       |""".stripMargin
}

class ZeroMqRobotLinkSpec extends ScalaTestWithActorTestKit(ZeroMqRobotLinkSpec.config) with AnyWordSpecLike
    with LogCapturing {
  import ZeroMqRobotLinkSpec._

  /** The gateway's settings with one ZeroMQ robot, `robotId` at `endpoint`. */
  private def gatewaySettings(robotId: Int, endpoint: String): GatewaySettings =
    GatewaySettings.fromConfig(
      ConfigFactory
        .parseString(s"""zeromq.robots = [{ id = $robotId, endpoint = "$endpoint" }]""")
        .withFallback(system.settings.config.getConfig("naogateway"))
    )

  private def call(connected: RobotEffects.Connected, module: String, method: String, params: RpcValue*): CallResult = {
    val results = createTestProbe[CallResult]()
    connected.response ! RobotAccess.Call(RpcCall(module, method, params.toVector), results.ref,
      timeout = Some(4.seconds))
    results.receiveMessage(6.seconds)
  }

  private def expectEvent[T](events: TestProbe[GatewayEvent], within: FiniteDuration)(
      pf: PartialFunction[GatewayEvent, T]): T =
    events.fishForMessagePF(within) {
      case e if pf.isDefinedAt(e) => FishingOutcome.Complete
      case _                      => FishingOutcome.ContinueAndIgnore
    }.collectFirst(pf).get

  "ZeroMqLoop" must {
    "end its thread and terminate its context promptly when stopped, and refuse work afterwards" in {
      val loop = new ZeroMqLoop("spec-loop", 100.millis)
      val executor = java.util.concurrent.Executors.newSingleThreadExecutor()
      try {
        loop.start(executor)
        val bound = scala.concurrent.Promise[String]()
        loop.submit { sockets =>
          val rep = sockets.socket(SocketType.REP)
          rep.bind(AnyPort)
          bound.success(rep.getLastEndpoint)
        }
        val endpoint = Await.result(bound.future, 10.seconds)
        endpoint should startWith("tcp://127.0.0.1:")
        // Without linger 0 a context with an open socket would never terminate; the wait bounds "promptly".
        Await.result(loop.stop(), 10.seconds)
        loop.submit(_ => ()) shouldBe false
        // The socket is closed: the port can be bound again.
        val again = new ZContext()
        try again.createSocket(SocketType.REP).bind(endpoint) shouldBe true
        finally again.close()
      } finally executor.shutdownNow()
    }
  }

  "ZeroMqSimulatedRobot" must {
    "answer the firmware's RPC over REP, the heartbeat's probe with the unknown-method error, and hold posture calls" in {
      val robot = new ZeroMqSimulatedRobot(FirmwareSettings(robotId = 31), AnyPort)
      robot.start()
      val endpoint = robot.boundEndpoint.get
      val context = new ZContext()
      try {
        val req = context.createSocket(SocketType.REQ)
        // jeromq clients now and then stall in the handshake; connect again soon rather than after 30 s.
        req.setHandshakeIvl(300)
        req.setReceiveTimeOut(5000)
        req.connect(endpoint)
        def ask(module: String, method: String, params: RpcValue*): RpcReply = {
          req.send(MessageContents(31, rpcRequest = Some(RpcCall(module, method, params.toVector, Some(9L)).toProto)).toProtobuf,
            0)
          val reply = MessageContents.parse(req.recv(0)).fold(e => fail(e.describe), identity)
          reply.robotId shouldBe 31
          RpcReply.fromProto(reply.rpcResponse.get)
        }
        ask("heartbeat", "probe") shouldBe RpcReply(Left(RpcReply.unknownMethod("heartbeat", "probe")), Some(9L))
        ask("motion", "getPosture").result shouldBe Right(Some(RpcValue.Text("sit")))
        val t0 = System.nanoTime()
        ask("motion", "posture", RpcValue.Text("stand")).result shouldBe Right(Some(RpcValue.Text("stand")))
        (System.nanoTime() - t0).nanos should be >= 1400.millis
        ask("motion", "walk", RpcValue.Number(0.1f), RpcValue.Number(0f), RpcValue.Number(0f)).result shouldBe
          Right(Some(RpcValue.Flag(true)))
        // Junk is answered too: a REP socket must answer every request to take the next.
        req.send(Array[Byte](1, 2, 3), 0)
        MessageContents.parse(req.recv(0)).toOption.flatMap(_.rpcResponse).flatMap(_.error).get should startWith(
          "bad parameters")
      } finally {
        context.close()
        robot.stop()
      }
      robot.isRunning shouldBe false
    }
  }

  "A ZeroMQ robot behind the gateway" must {
    "come online, serve calls and the heartbeat through the link, go offline when stopped and come back when restarted" in {
      val robot = new ZeroMqSimulatedRobot(FirmwareSettings(robotId = 20), AnyPort)
      robot.start()
      try {
        val events = createTestProbe[GatewayEvent]()
        // A restarted robot binds the same port again, where the gateway keeps looking for it.
        val gateway = spawn(Gateway(gatewaySettings(20, robot.boundEndpoint.get)))
        gateway ! GatewayAccess.Subscribe(events.ref)
        expectEvent(events, 10.seconds) { case RobotOnline(20, _) => () }
        val snapshot = expectEvent(events, 3.seconds) { case RobotStatusUpdated(s) if s.robotId == 20 => s }
        snapshot.posture shouldBe Some(Posture.Sit)
        snapshot.batteryVoltage.get shouldBe 12.4 +- 0.1

        val connected = GatewayInternals.connect(gateway, 20).get

        // A posture motion holds the REP socket for 1.5 s; the heartbeat must not take that for a lost robot.
        call(connected, "motion", "posture", RpcValue.Text("stand")).result shouldBe Right(Some(RpcValue.Text("stand")))
        call(connected, "motion", "walk", RpcValue.Number(0.1f), RpcValue.Number(0f), RpcValue.Number(0f)).result shouldBe
          Right(Some(RpcValue.Flag(true)))
        call(connected, "heartbeat", "probe").result shouldBe
          Left(RobotFailure.RobotError(20, RpcReply.unknownMethod("heartbeat", "probe")))
        expectEvent(events, 2.seconds) {
          case RobotStatusUpdated(s) if s.posture.contains(Posture.Stand) || s.posture.contains(Posture.Walking) => ()
        }

        robot.stop()
        // quiet-after + 3 probes = 3.6 s after the last keep-alive; the rest is slack for a loaded machine.
        val offline = expectEvent(events, 15.seconds) { case RobotOffline(20, reason) => reason }
        offline should include("unanswered probes")
        call(connected, "motion", "getPosture").result shouldBe Left(RobotFailure.RobotOffline(20))

        robot.start()
        // Back online, and the status poll saw the uptime go back: a new session (reported in either order).
        var seen = Set.empty[String]
        events.fishForMessage(15.seconds) {
          case RobotOnline(20, _) =>
            seen += "online"
            if (seen.size == 2) FishingOutcome.Complete else FishingOutcome.Continue
          case RobotRestarted(20, _, _) =>
            seen += "restarted"
            if (seen.size == 2) FishingOutcome.Complete else FishingOutcome.Continue
          case _ => FishingOutcome.ContinueAndIgnore
        }
        call(connected, "motion", "getPosture").result shouldBe Right(Some(RpcValue.Text("sit")))
        testKit.stop(gateway)
      } finally robot.stop()
    }
  }

  "The ZeroMQ robot link" must {
    "leave its status polls to the robot's sender, and drop a send when nobody listens" in {
      // Bound but never listening: connecting is refused, and no one else can take the port meanwhile.
      val deaf = new Socket()
      try {
        deaf.bind(new InetSocketAddress("127.0.0.1", 0))
        val settings = GatewaySettings(system).zeromq
        val owner = createTestProbe[ZeroMqRobotLink.Event]()
        val sender = createTestProbe[NoResponseActor.Command]()
        val outcomes = createTestProbe[Outbox.Outcome]()
        val link = spawn(ZeroMqRobotLink(21, s"tcp://127.0.0.1:${deaf.getLocalPort}", settings, owner.ref,
            sender.ref, ZeroMqRobotLink.SharedLoop(system).loop))
        // The gate and the in-flight cap are the sender's and the outbox's: the link submits its polls to the sender.
        val due = Vector.fill(3)(sender.expectMessageType[NoResponseActor.Submit](settings.statusInterval * 3)).map {
          case NoResponseActor.Submit(RobotFrames.Outbound.CallOut(call), Priority.Heartbeat, key, _, Some(_), None) =>
            key shouldBe call.callId
            call
          case other => fail(s"not a status poll: $other")
        }
        due.map(c => c.module -> c.method) shouldBe ZeroMqRobotLink.StatusCalls
        due.flatMap(_.callId).map(CallId.ownerOf) shouldBe Vector.fill(3)(Some(CallId.Owner.StatusPoll))
        // Nobody listens on the port: with immediate queueing the request is dropped, not kept for later.
        link ! ZeroMqRobotLink.Send(Array[Byte](8, 1), Some(outcomes.ref), 6L)
        outcomes.expectMessageType[Outbox.Dropped].tag shouldBe 6L
        testKit.stop(link)
      } finally deaf.close()
    }
  }
}
