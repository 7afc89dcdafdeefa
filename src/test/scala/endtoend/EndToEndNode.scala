package endtoend

import java.net.InetSocketAddress

import scala.concurrent.Await
import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.ActorTestKit
import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, ActorSystem}
import akka.cluster.typed.{Cluster, Join}
import com.typesafe.config.{Config, ConfigFactory}

import naogateway.access.GatewayAccess
import naogateway.api.{GatewayAddresses, RobotSnapshot}
import naogateway.gateway.{Gateway, GatewaySettings}
import naogateway.sim._
import naogateway.testkit.TestLoopback
import robotmiddleware._
import robotmiddleware.cluster.MiddlewareCluster

/** The whole stack as users meet it, for EndToEndSpec and the follower bench: a gateway node (gateway, middleware,
  * simulated robots on loopback UDP) and app nodes, actor systems of their own that reach it only through the cluster
  * and `RobotInterface`. `shutdown()` ends them all.
  */
final class EndToEndNode {

  // Heartbeats may pause 10 s: a JVM stalled on a loaded machine must not make a node unreachable mid-test.
  private val common: Config = ConfigFactory.parseString("""
      |akka.cluster.jmx.multi-mbeans-in-same-jvm = on
      |akka.cluster.split-brain-resolver.stable-after = 1s
      |akka.cluster.failure-detector.acceptable-heartbeat-pause = 10s
      |naogateway.link.bind-address = "127.0.0.1"
      |naogateway.link.robot-port = 0
      |naogateway.game-controller.enabled = off
      |""".stripMargin)

  /** The gateway node's test kit. */
  val gatewayNode: ActorTestKit = ActorTestKit(
    MiddlewareCluster.start(
      Behaviors.empty,
      MiddlewareCluster.GatewayRole,
      ConfigFactory.parseString("robotmiddleware.cluster.gateway-port = 0\nakka.cluster.seed-nodes = []").withFallback(
        common)
    )
  )
  private val cluster = Cluster(gatewayNode.system)
  cluster.manager ! Join(cluster.selfMember.address)
  private val gatewayPort = cluster.selfMember.address.port.get

  /** The gateway node's cluster address, for an app node to join. */
  val gatewayAddress: akka.actor.Address = cluster.selfMember.address

  /** The gateway on the gateway node. */
  val gateway: ActorRef[GatewayAccess.Command] = gatewayNode.spawn(Gateway(GatewaySettings(gatewayNode.system)),
    "gateway")

  /** The middleware on the gateway node. */
  val middleware: ActorRef[RobotMiddleware.Command] =
    gatewayNode.spawn(RobotMiddleware(gateway, MiddlewareSettings(gatewayNode.system)), "middleware")

  /** Where the gateway listens for robots. */
  val robotPort: InetSocketAddress = {
    val probe = gatewayNode.createTestProbe[GatewayAddresses]()
    gateway ! GatewayAccess.GetAddresses(probe.ref)
    probe.receiveMessage(10.seconds).robots
  }
  private var appNodes = List.empty[ActorSystem[_]]

  /** Ends the app nodes and the gateway node. */
  def shutdown(): Unit = {
    appNodes.foreach(_.terminate())
    gatewayNode.shutdownTestKit()
  }

  /** A new app node that joins the gateway node's cluster, at once or (`join` off) only when told to join
    * [[gatewayAddress]].
    */
  def appNode(join: Boolean = true): ActorSystem[Nothing] = {
    val seeds = if (join) "" else "akka.cluster.seed-nodes = []"
    val node = MiddlewareCluster.start[Nothing](
      Behaviors.empty,
      MiddlewareCluster.AppRole,
      ConfigFactory.parseString(s"robotmiddleware.cluster.gateway-port = $gatewayPort\n$seeds").withFallback(common)
    )
    appNodes ::= node
    node
  }

  /** An app named `name` on `node`, connected to the middleware once it finds it. */
  def connect(node: ActorSystem[_], name: String, priority: Int, within: FiniteDuration): RobotInterface =
    Await.result(RobotClient.find(node, within).flatMap(RobotClient.connect(node, _, name, priority))(
        node.executionContext), within + 5.seconds)

  /** Starts simulated robot `id` on the gateway node, sending to `to`. */
  def spawnRobot(id: Int, to: InetSocketAddress = robotPort,
      firmware: FirmwareSettings => FirmwareSettings = identity): ActorRef[SimulatedRobot.Command] = {
    val probe = gatewayNode.createTestProbe[SimulatedRobot.StartResult]()
    gatewayNode.spawn(
      SimulatedRobot(
        SimulatedRobotSettings(firmware(FirmwareSettings(id)), to,
          bindAddress = new InetSocketAddress(TestLoopback.address(), 0), faithfulLink = false),
        Some(probe.ref)
      ),
      s"robot-$id"
    )
    probe.receiveMessage(10.seconds) match {
      case SimulatedRobot.Started(_, ref, _) => ref
      case other                             => throw new IllegalStateException(s"robot $id did not start: $other")
    }
  }

  /** What the simulated robot is doing now. */
  def view(robot: ActorRef[SimulatedRobot.Command]): RobotView = {
    val probe = gatewayNode.createTestProbe[RobotView]()
    robot ! SimulatedRobot.GetState(probe.ref)
    probe.receiveMessage()
  }

  /** Whether the gateway has robot `id` online now. */
  def isOnline(id: Int): Boolean = {
    val probe = gatewayNode.createTestProbe[Vector[RobotSnapshot]]()
    gateway ! GatewayAccess.GetRobots(probe.ref)
    probe.receiveMessage().exists(r => r.robotId == id && r.online)
  }
}
