package endtoend

import naogateway.wire.ActuatorGroup

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.LogCapturing
import akka.actor.typed.scaladsl.AskPattern._
import akka.actor.testkit.typed.scaladsl.TestProbe
import akka.actor.typed.{ActorRefResolver, ActorSystem}
import akka.cluster.typed.{Cluster, Join}
import akka.stream.Materializer
import akka.stream.scaladsl.Sink
import org.scalatest.BeforeAndAfterAll
import org.scalatest.concurrent.{Eventually, ScalaFutures}
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import apps.BallFollower
import naogateway.testkit.TestLoopback
import naogateway.api.{RobotFailure, VisionFrame}
import naogateway.sim._
import naogateway.sim.network.LossyNetwork
import naogateway.wire.Posture
import robotmiddleware._

/** The whole stack as users meet it: a gateway node (gateway, middleware, simulated robots on loopback UDP) and apps in
  * actor systems of their own that reach it only through the cluster and `RobotInterface`.
  */
class EndToEndSpec extends AnyWordSpec with Matchers with ScalaFutures with Eventually with BeforeAndAfterAll
    with LogCapturing {

  implicit override val patienceConfig: PatienceConfig = PatienceConfig(30.seconds, 100.millis)

  private val e2e = new EndToEndNode
  import e2e.{appNode, gatewayNode, middleware, robotPort, spawnRobot, view}

  override def afterAll(): Unit = e2e.shutdown()

  private def connect(node: ActorSystem[_], name: String, priority: Int): RobotInterface =
    e2e.connect(node, name, priority, 30.seconds)

  private def online(id: Int): Unit = eventually(e2e.isOnline(id) shouldBe true)

  "An app in its own actor system" must {
    "command a simulated robot through the middleware and read its status stream" in {
      val sim = spawnRobot(11)
      online(11)
      val node = appNode()
      val app = connect(node, "walker", 1)
      implicit val system: ActorSystem[_] = node
      app.acquire(11, ActuatorGroup.Walk).futureValue
      app.posture(11, Posture.Stand).futureValue shouldBe Posture.Stand
      app.walk(11, 0.2, 0.0, 0.0).futureValue
      val walking = app.status(11).filter(_.posture.contains(Posture.Walking)).runWith(Sink.head)
      walking.futureValue.robotId shouldBe 11
      // The middleware keeps the walk alive past the robot's 500 ms lease: the robot walks on for well over the 0.1 m
      /* one lease carries it at 0.2 m/s. The distance adds up across a late refresh, which a look at the posture would
       * not. */
      val start = view(sim).pose
      eventually(math.hypot(view(sim).pose.x - start.x, view(sim).pose.y - start.y) should be > 0.3)
      app.stop(11).futureValue
      eventually(view(sim).posture shouldBe Posture.Stand)
    }

    "serve robotctl through the gateway node's control port: one status line per robot, and calls" in {
      spawnRobot(17)
      online(17)
      val control = gatewayNode.spawn(apps.control.ControlServer(middleware,
          apps.control.ControlSettings(gatewayNode.system).copy(host = "127.0.0.1", port = 0)), "control")
      val probe = gatewayNode.createTestProbe[InetSocketAddress]()
      control ! apps.control.ControlServer.GetAddress(probe.ref)
      val address = s"127.0.0.1:${probe.receiveMessage(10.seconds).getPort}"
      def robotctl(args: String*): (Int, Vector[String], Vector[String]) = {
        val out = Vector.newBuilder[String]
        val err = Vector.newBuilder[String]
        val code = naogateway.launcher.RobotCtl.run("--control" +: address +: args, _ => None, out += _, err += _)
        (code, out.result(), err.result())
      }
      val (code, status, errors) = robotctl("status")
      withClue(errors) { code shouldBe 0 }
      val line = status.find(_.startsWith("17 ")).getOrElse(fail(status.mkString("\n")))
      // The robot at its own loopback address and receive port (docs/protocol.md section 2).
      Seq(":3838 ", "online", "good", "V", "sit", "striker", "%").foreach(line should include(_))
      robotctl("call", "17", "motion", "getPosture") shouldBe ((0, Vector("robot 17: motion.getPosture -> Text(sit)"),
        Vector.empty))
      robotctl("call", "4711", "motion", "getPosture") shouldBe ((1, Vector.empty,
        Vector("robotctl: no robot 4711 is known")))
      gatewayNode.stop(control)
    }

    "stop its robot and free its lease when the app's system dies, so another app gets it" in {
      val sim = spawnRobot(12)
      online(12)
      val doomed = appNode()
      val first = connect(doomed, "doomed", 1)
      first.acquire(12, ActuatorGroup.Walk).futureValue
      first.posture(12, Posture.Stand).futureValue
      first.walk(12, 0.2, 0.0, 0.0).futureValue
      val second = connect(appNode(), "patient", 1)
      second.acquire(12, ActuatorGroup.Walk).failed.futureValue shouldBe a[RobotFailure.LeaseNotHeld]
      doomed.terminate()
      doomed.whenTerminated.futureValue
      eventually(view(sim).posture shouldBe Posture.Stand)
      eventually(second.acquire(12, ActuatorGroup.Walk).futureValue)
    }

    "see its robot stopped and sat down when the battery runs low, and motion refused" in {
      val sim = spawnRobot(13)
      online(13)
      val node = appNode()
      val app = connect(node, "walker", 1)
      implicit val system: ActorSystem[_] = node
      val safetyStop = app.appEvents.collect { case e: AppEvent.SafetyStop => e }.runWith(Sink.head)
      app.acquire(13, ActuatorGroup.Walk).futureValue
      app.posture(13, Posture.Stand).futureValue
      app.walk(13, 0.1, 0.0, 0.0).futureValue
      sim ! SimulatedRobot.SetBattery(10.4)
      eventually(view(sim).posture shouldBe Posture.Sit)
      app.walk(13, 0.1, 0.0, 0.0).failed.futureValue shouldBe a[RobotFailure.SafetyHold]
      app.posture(13, Posture.Stand).failed.futureValue shouldBe a[RobotFailure.SafetyHold]
      safetyStop.futureValue.robotId shouldBe 13
      app.close()
    }

    "get fast robot-offline failures when the link is lost, while the robot stops its interrupted walk itself" in {
      val network = LossyNetwork.start(seed = 4)
      try {
        val proxy = network.addProxy(robotPort, TestLoopback.address())
        val sim = spawnRobot(14, to = proxy.clientSide)
        online(14)
        val app = connect(appNode(), "walker", 1)
        app.acquire(14, ActuatorGroup.Walk).futureValue
        app.posture(14, Posture.Stand).futureValue
        app.walk(14, 0.2, 0.0, 0.0).futureValue
        network.partition(proxy, on = true)
        eventually {
          val begin = System.nanoTime()
          app.call(14, "system", "ping").failed.futureValue shouldBe RobotFailure.RobotOffline(14)
          (System.nanoTime() - begin).nanos should be < 1.second
        }
        eventually(view(sim).posture shouldBe Posture.Stand)
        network.partition(proxy, on = false)
        online(14)
        app.call(14, "system", "ping").futureValue.isDefined shouldBe true
      } finally network.stop()
    }

    "have its robot's camera off once its camera stream ends, though the stream began before its node was up" in {
      val sim = spawnRobot(19)
      online(19)
      def camera(): Boolean = view(sim).debugEnabled.contains("havimo.regions")
      // A node that joins only when told: its stream begins while the gateway node has not seen it Up, when Akka
      // drops a death watch of an actor on it.
      val node = appNode(join = false)
      val resolver = ActorRefResolver(node)
      val middlewareThere =
        resolver.resolveActorRef[RobotMiddleware.Command](ActorRefResolver(gatewayNode.system).toSerializationFormat(
            middleware))
      val frames = TestProbe[VisionFrame]()(node)
      middlewareThere ! RobotMiddleware.WatchVision(19, frames.ref, grid = false)
      Cluster(node).manager ! Join(e2e.gatewayAddress)
      frames.receiveMessage(30.seconds)
      camera() shouldBe true
      frames.stop()
      eventually(camera() shouldBe false)
      // A stream of an app whose actor system ends.
      val app = connect(node, "watcher", 1)
      app.vision(19).runWith(Sink.ignore)(Materializer(node))
      eventually(camera() shouldBe true)
      node.terminate()
      node.whenTerminated.futureValue
      eventually(camera() shouldBe false)
    }

    "lose a lease to a higher-priority app and be told so" in {
      spawnRobot(15)
      online(15)
      val node = appNode()
      val low = connect(node, "follower", 1)
      val high = connect(appNode(), "referee", 9)
      implicit val system: ActorSystem[_] = node
      val lowEvents = low.appEvents.takeWithin(20.seconds).runWith(Sink.head)
      low.acquire(15, ActuatorGroup.Walk).futureValue
      high.acquire(15, ActuatorGroup.Walk).futureValue
      lowEvents.futureValue shouldBe AppEvent.LeasePreempted(15, ActuatorGroup.Walk, "referee")
      low.stop(15).failed.futureValue shouldBe RobotFailure.LeaseNotHeld(15, ActuatorGroup.Walk, Some("referee"))
      high.stop(15).futureValue
    }
  }

  "The ball follower" must {
    // Through the cluster: the lease, standing up, the camera's frames, walks towards the ball. The whole chase (1.5 m,
    // about 20 s) is the follower bench's (bench.FollowerBench); the control's own closed loop reaching the ball is
    // BallFollowerControlSpec's, in simulated time.
    "take its robot from its own actor system and walk it towards the simulated ball" in {
      val ball = Scene(0.5, 0.3)
      val sim = spawnRobot(16, firmware = _.copy(startPose = Pose(-1.0, 0.0, 0.0), scene = ball))
      online(16)
      val node = appNode()
      val robotInterface = connect(node, "ball-follower", 1)
      val before = ball.ballDistance(view(sim).pose)
      // The follower lives in the app's own actor system, next to its RobotInterface.
      val follower = node.systemActorOf(BallFollower(robotInterface, 16), "follower-16")
      eventually(timeout(60.seconds), interval(100.millis)) {
        ball.ballDistance(view(sim).pose) should be < before - 0.3
      }
      val progress =
        follower.ask(BallFollower.GetProgress.apply)(akka.util.Timeout(5.seconds), node.scheduler).futureValue
      progress.frames should be > 0L
      progress.lastDistance shouldBe defined
    }

    "rest the camera at the ball and take a look now and then" in {
      // The ball 0.6 m ahead: in sight at once, reached within a few steps.
      val ball = Scene(0.6, 0.0)
      val sim = spawnRobot(18, firmware = _.copy(startPose = Pose(0.0, 0.0, 0.0), scene = ball))
      online(18)
      val node = appNode()
      val follower = node.systemActorOf(BallFollower(connect(node, "ball-follower-rest", 1), 18), "follower-18")
      def progress(): BallFollower.Progress =
        follower.ask(BallFollower.GetProgress.apply)(akka.util.Timeout(5.seconds), node.scheduler).futureValue
      def camera(): Boolean = view(sim).debugEnabled.contains("havimo.regions")
      eventually(timeout(60.seconds), interval(100.millis))(progress().reached shouldBe true)
      // At the ball the camera goes off after a look's frames, comes on for the next look, and goes off again.
      eventually(timeout(30.seconds), interval(20.millis))(camera() shouldBe false)
      val atRest = progress().frames
      eventually(timeout(30.seconds), interval(20.millis))(camera() shouldBe true)
      eventually(timeout(30.seconds), interval(20.millis))(camera() shouldBe false)
      progress().frames should be > atRest
      progress().reached shouldBe true
    }
  }
}
