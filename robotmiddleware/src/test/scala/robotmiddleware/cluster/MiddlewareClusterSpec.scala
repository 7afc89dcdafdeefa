package robotmiddleware.cluster

import naogateway.wire.ActuatorGroup

import scala.annotation.tailrec
import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.util.{Failure, Success, Try}

import akka.Done
import akka.actor.testkit.typed.FishingOutcome
import akka.actor.testkit.typed.scaladsl.{ActorTestKit, LogCapturing, TestProbe}
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, ActorSystem, Behavior}
import akka.cluster.ClusterEvent.MemberDowned
import akka.cluster.typed.{Cluster, Join, Subscribe}
import akka.stream.Materializer
import akka.stream.scaladsl.Sink
import com.typesafe.config.{Config, ConfigFactory}
import org.scalatest.BeforeAndAfterAll
import org.scalatest.concurrent.ScalaFutures
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.access.{GatewayAccess, RobotAccess}
import naogateway.api.{
  CallResult,
  GameStateUpdated,
  GatewayEvent,
  LinkQuality,
  LinkQualityChanged,
  LinkStats,
  RobotEvent,
  RobotFailure,
  RobotOnline,
  RobotSnapshot,
  RobotStatusUpdated,
  VisionFrame
}
import naogateway.wire.RpcValue
import naogateway.wire.gamecontroller.GameControlData
import robotmiddleware._

/** Nodes of one cluster on loopback, each its own actor system in this JVM: A runs the middleware in front of a fake
  * gateway and robot, B and C are app nodes that reach it only through the cluster.
  */
class MiddlewareClusterSpec
    extends AnyWordSpec
    with Matchers
    with ScalaFutures
    with BeforeAndAfterAll
    with LogCapturing {
  import CrossNodeSerializationSpec.{gameData, grid, linkStats, snapshot}
  import MiddlewareClusterSpec._

  implicit override val patienceConfig: PatienceConfig = PatienceConfig(20.seconds, 50.millis)

  private val nodeA =
    ActorTestKit(MiddlewareCluster.start(Behaviors.empty, MiddlewareCluster.GatewayRole, gatewayOverrides))
  private val clusterA = Cluster(nodeA.system)
  // Port 0 cannot be a seed in anybody's config: the gateway joins itself, the apps get its real port.
  clusterA.manager ! Join(clusterA.selfMember.address)
  private val portA = clusterA.selfMember.address.port.get

  private val response = nodeA.createTestProbe[RobotAccess.Call]()
  private val vision = nodeA.createTestProbe[RobotAccess.RegisterVision]()
  private val subscriptions = nodeA.createTestProbe[ActorRef[GatewayEvent]]()
  private val robot =
    nodeA.spawn(fakeRobot(RobotAccess.Opened(7, response.ref, vision.ref)), "robot-7")
  private val gateway = nodeA.spawn(fakeGateway(robot, subscriptions.ref), "gateway")
  private val middleware = nodeA.spawn(RobotMiddleware(gateway, MiddlewareSettings(nodeA.system)), "middleware")
  private val gatewayEvents = subscriptions.receiveMessage()

  private lazy val nodeB = appNode(ConfigFactory.empty())
  private lazy val fallback = RobotClient.connect(nodeA.system, middleware, "fallback", priority = 1).futureValue

  // App nodes a failed test left running are shut down with the gateway node.
  private var appNodes = List.empty[ActorTestKit]

  override protected def afterAll(): Unit = {
    appNodes.foreach(_.shutdownTestKit())
    nodeA.shutdownTestKit()
    super.afterAll()
  }

  /** Answers the robot's calls (with `answer` for the one named `name`, nothing for others) until `name` came. */
  private def answerUntil(name: String, answer: Option[RpcValue] = None): RobotAccess.Call =
    response
      .fishForMessage(30.seconds, s"a call of $name") {
        case c: RobotAccess.Call =>
          val wanted = c.call.name == name
          c.replyTo ! CallResult(7, c.call.name, Right(if (wanted) answer else None))
          if (wanted) FishingOutcome.Complete else FishingOutcome.Continue
        case _ => FishingOutcome.Continue
      }
      .collect { case c: RobotAccess.Call => c }
      .last

  /** A stream subscription is a one-way message from the app's node: nothing says when the middleware has it.
    * Publishing again until the first element arrives avoids guessing a delay.
    */
  private def publishUntilSeen[T](probe: TestProbe[T], within: FiniteDuration = 20.seconds)(publish: => Unit): T = {
    val deadline = within.fromNow
    @tailrec def loop(): T = {
      publish
      Try(probe.receiveMessage(300.millis)) match {
        case Success(seen)                        => seen
        case Failure(_) if deadline.hasTimeLeft() => loop()
        case Failure(e)                           => throw e
      }
    }
    loop()
  }

  private def appNode(overrides: Config): ActorTestKit = {
    val config = overrides.withFallback(appOverrides(portA))
    val node = ActorTestKit(MiddlewareCluster.start(Behaviors.empty, MiddlewareCluster.AppRole, config))
    appNodes ::= node
    node
  }

  private def connect(node: ActorTestKit, name: String, priority: Int): RobotInterface = {
    val system: ActorSystem[_] = node.system
    val ec = system.executionContext
    RobotClient.find(system, 20.seconds).flatMap(RobotClient.connect(system, _, name, priority))(ec).futureValue
  }

  "MiddlewareCluster.config" must {
    "give each role its port, the gateway as seed, keep-oldest downing and no Java serialization" in {
      val gatewayAt4711 = ConfigFactory.parseString("robotmiddleware.cluster.gateway-port = 4711")
      val app = MiddlewareCluster.config(MiddlewareCluster.AppRole, gatewayAt4711)
      app.getStringList("akka.cluster.roles").asScala shouldBe Seq("app")
      app.getInt("akka.remote.artery.canonical.port") shouldBe 0
      app.getStringList("akka.cluster.seed-nodes").asScala shouldBe Seq("akka://robots@127.0.0.1:4711")
      app.getBoolean("akka.actor.allow-java-serialization") shouldBe false
      app.getString("akka.actor.provider") shouldBe "cluster"
      app.getString("akka.cluster.split-brain-resolver.active-strategy") shouldBe "keep-oldest"
      app.getString("akka.cluster.split-brain-resolver.keep-oldest.role") shouldBe MiddlewareCluster.GatewayRole
      app.getBoolean("akka.cluster.split-brain-resolver.keep-oldest.down-if-alone") shouldBe false
      app.getDuration("akka.cluster.split-brain-resolver.stable-after").toSeconds shouldBe 7
      val gw = MiddlewareCluster.config(MiddlewareCluster.GatewayRole)
      gw.getStringList("akka.cluster.roles").asScala shouldBe Seq("gateway")
      gw.getInt("akka.remote.artery.canonical.port") shouldBe 25520
      gw.getStringList("akka.cluster.seed-nodes").asScala shouldBe Seq("akka://robots@127.0.0.1:25520")
    }
  }

  "An app on another node" must {
    "find the middleware, lease a robot, command it and read its streams" in {
      implicit val materializer: Materializer = Materializer.matFromSystem(nodeB.system)
      MiddlewareCluster.up(nodeB.system).futureValue shouldBe Done
      val app = connect(nodeB, "remote-app", priority = 5)

      gatewayEvents ! RobotOnline(7, snapshot.address)
      gatewayEvents ! RobotStatusUpdated(snapshot)
      app.robots().futureValue shouldBe Vector(snapshot)

      val status = nodeB.createTestProbe[RobotSnapshot]()
      app.status(7).runWith(Sink.foreach(status.ref ! _))
      status.expectMessage(10.seconds, snapshot)
      val later = snapshot.copy(batteryVoltage = Some(11.4), receivedAtNanos = snapshot.receivedAtNanos + 1)
      gatewayEvents ! RobotStatusUpdated(later)
      status.expectMessage(10.seconds, later)

      app.acquire(7, ActuatorGroup.Walk, ActuatorGroup.Head).futureValue shouldBe Done
      val walked = app.walk(7, 0.2, 0.0, 0.1)
      answerUntil("motion.walk").call.params shouldBe Vector(0.2f, 0.0f, 0.1f).map(RpcValue.Number(_))
      walked.futureValue shouldBe Done
      val battery = app.call(7, "system", "battery")
      answerUntil("system.battery", Some(RpcValue.Number(11.4f)))
      battery.futureValue shouldBe Some(RpcValue.Number(11.4f))
      app.arms(7, 0, 0, 0, 0).failed.futureValue shouldBe RobotFailure.LeaseNotHeld(7, ActuatorGroup.Arms, None)

      val frames = nodeB.createTestProbe[VisionFrame]()
      app.vision(7, grid = true).runWith(Sink.foreach(frames.ref ! _))
      val register = vision.expectMessageType[RobotAccess.RegisterVision](10.seconds)
      register.grid shouldBe true
      register.subscriber ! grid
      frames.expectMessage(10.seconds, grid)

      val stats = nodeB.createTestProbe[LinkStats]()
      app.linkStats(7).runWith(Sink.foreach(stats.ref ! _))
      stats.expectMessage(10.seconds, linkStats)

      val events = nodeB.createTestProbe[RobotEvent]()
      app.robotEvents.runWith(Sink.foreach(events.ref ! _))
      publishUntilSeen(events)(gatewayEvents ! LinkQualityChanged(7, LinkQuality.Degraded)) shouldBe
        LinkQualityChanged(7, LinkQuality.Degraded)

      val games = nodeB.createTestProbe[GameControlData]()
      app.gameState.runWith(Sink.foreach(games.ref ! _))
      publishUntilSeen(games)(gatewayEvents ! GameStateUpdated(gameData)) shouldBe gameData

      val appEvents = nodeB.createTestProbe[AppEvent]()
      app.appEvents.runWith(Sink.foreach(appEvents.ref ! _))
      app.robots().futureValue // the local subscription on node B is in place long before this round trip ends
      val referee = RobotClient.connect(nodeA.system, middleware, "referee", priority = 9).futureValue
      referee.acquire(7, ActuatorGroup.Head).futureValue shouldBe Done
      appEvents.expectMessage(10.seconds, AppEvent.LeasePreempted(7, ActuatorGroup.Head, "referee"))
      referee.close()
    }

    "lose its leases when its node leaves, and its walking robot is stopped" in {
      fallback.acquire(7, ActuatorGroup.Walk).failed.futureValue shouldBe
        RobotFailure.LeaseNotHeld(7, ActuatorGroup.Walk, Some("remote-app"))
      nodeB.shutdownTestKit()
      answerUntil("motion.stop")
      fallback.acquire(7, ActuatorGroup.Walk).futureValue shouldBe Done
    }

    "be downed when its node dies without leaving, and lose its leases then" in {
      fallback.release(7, ActuatorGroup.Walk)
      answerUntil("motion.stop")
      val downed = nodeA.createTestProbe[MemberDowned]()
      clusterA.subscriptions ! Subscribe(downed.ref, classOf[MemberDowned])
      // No coordinated shutdown on terminate: the node vanishes without telling the cluster it leaves.
      val crash = ConfigFactory.parseString("akka.coordinated-shutdown.run-by-actor-system-terminate = off")
      val nodeC = appNode(crash)
      val addressC = Cluster(nodeC.system).selfMember.address
      MiddlewareCluster.up(nodeC.system).futureValue shouldBe Done
      val crashing = connect(nodeC, "crashing-app", priority = 5)
      crashing.acquire(7, ActuatorGroup.Walk).futureValue shouldBe Done
      val walked = crashing.walk(7, 0.1, 0.0, 0.0)
      answerUntil("motion.walk")
      walked.futureValue shouldBe Done

      nodeC.shutdownTestKit()
      downed.expectMessageType[MemberDowned](30.seconds).member.address shouldBe addressC
      answerUntil("motion.stop")
      fallback.acquire(7, ActuatorGroup.Walk).futureValue shouldBe Done
    }

    "reach a robot through both doors: a send refused without its lease, then before a call, its answer dropped" in {
      val nodeD = appNode(ConfigFactory.empty())
      MiddlewareCluster.up(nodeD.system).futureValue shouldBe Done
      val app = connect(nodeD, "two-doors", priority = 5)
      app.send(7, Operation.Head(0.3, 0.0)).failed.futureValue shouldBe
        RobotFailure.LeaseNotHeld(7, ActuatorGroup.Head, None)
      app.acquire(7, ActuatorGroup.Head).futureValue shouldBe Done
      val sent = app.send(7, Operation.Head(0.3, 0.0))
      val called = app.call(7, "system", "battery")
      // The robot's one command owner gets both, the send first; the robot's error to the send goes nowhere.
      val seen = response
        .fishForMessage(30.seconds, "the send, then the call") {
          case c: RobotAccess.Call if c.call.name == "motion.head" =>
            c.idempotent shouldBe Some(false) // a send is sent once
            c.replyTo ! CallResult(7, c.call.name, Left(RobotFailure.RobotError(7, "head is busy")))
            FishingOutcome.Continue
          case c: RobotAccess.Call if c.call.name == "system.battery" =>
            c.replyTo ! CallResult(7, c.call.name, Right(Some(RpcValue.Number(11.9f))))
            FishingOutcome.Complete
          case c: RobotAccess.Call =>
            c.replyTo ! CallResult(7, c.call.name, Right(None))
            FishingOutcome.ContinueAndIgnore
          case _ => FishingOutcome.ContinueAndIgnore
        }
        .collect { case c: RobotAccess.Call => c.call.name }
      seen shouldBe Seq("motion.head", "system.battery")
      sent.futureValue shouldBe Done
      called.futureValue shouldBe Some(RpcValue.Number(11.9f))
      app.close()
    }
  }
}

/** The nodes' test settings and the fake gateway side behind the middleware. */
object MiddlewareClusterSpec {

  // Heartbeats may pause 10 s: a JVM stalled on a loaded machine must not make a node unreachable mid-test. The test
  // of a crashed node waits that long for its unreachability, well inside its 30 s deadlines.
  private val common: Config = ConfigFactory.parseString(
    """akka.cluster.jmx.multi-mbeans-in-same-jvm = on
      |akka.cluster.split-brain-resolver.stable-after = 1s
      |akka.cluster.failure-detector.acceptable-heartbeat-pause = 10s
      |robotmiddleware.link-stats-interval = 300ms
      |""".stripMargin
  )

  /** The gateway node: any free port, no seed nodes (it joins itself). */
  val gatewayOverrides: Config =
    ConfigFactory
      .parseString("robotmiddleware.cluster.gateway-port = 0\nakka.cluster.seed-nodes = []")
      .withFallback(common)

  /** An app node whose seed is the gateway at `gatewayPort`, as an app on another machine would configure it. */
  def appOverrides(gatewayPort: Int): Config =
    ConfigFactory.parseString(s"robotmiddleware.cluster.gateway-port = $gatewayPort").withFallback(common)

  /** The robot actor as far as the middleware uses it: its children, its snapshot (online) and its link figures. */
  def fakeRobot(children: RobotAccess.Opened): Behavior[RobotAccess.Command] = Behaviors.receiveMessage {
    case RobotAccess.Open(replyTo) =>
      replyTo ! children
      Behaviors.same
    case RobotAccess.GetSnapshot(replyTo) =>
      replyTo ! CrossNodeSerializationSpec.snapshot
      Behaviors.same
    case RobotAccess.GetLinkStats(replyTo) =>
      replyTo ! CrossNodeSerializationSpec.linkStats
      Behaviors.same
  }

  /** The gateway as far as the middleware uses it: one robot, 7, its snapshot, and the subscription to its events. */
  def fakeGateway(
      robot: ActorRef[RobotAccess.Command],
      subscriptions: ActorRef[ActorRef[GatewayEvent]]
  ): Behavior[GatewayAccess.Command] =
    Behaviors.receiveMessage {
      case GatewayAccess.Subscribe(subscriber) =>
        subscriptions ! subscriber
        Behaviors.same
      case GatewayAccess.GetRobotAccess(robotId, replyTo) =>
        replyTo ! Some(robot).filter(_ => robotId == 7)
        Behaviors.same
      case GatewayAccess.GetRobots(replyTo) =>
        // What the real gateway would collect from robot 7's actor.
        replyTo ! Vector(CrossNodeSerializationSpec.snapshot)
        Behaviors.same
      case _ => Behaviors.unhandled
    }
}
