package bench

import scala.collection.immutable.ListMap
import scala.concurrent.Await
import scala.concurrent.duration._

import akka.actor.typed.scaladsl.AskPattern._

import apps.BallFollower
import endtoend.EndToEndNode
import naogateway.sim.{Pose, Scene}

/** The ball follower's long chase, as the demo runs it: the follower in an app node of its own, reaching the gateway
  * node's simulated robot through the cluster (endtoend.EndToEndNode, the stack EndToEndSpec drives), the robot 1.5 m
  * from the ball ((-1, 0) facing +x, the ball at (0.5, 0.3)). EndToEndSpec checks that the follower walks the robot
  * towards the ball; the whole chase takes about 20 s, so it is a figure here.
  *
  *   - `follower_first_frame_s`: from the follower's start to its first camera frame (the lease, standing up, the
  *     camera switched on).
  *   - `follower_reach_s`: from the follower's start until it says it reached the ball (NaN if not within 90 s).
  *   - `follower_final_distance_m`: the simulated robot's distance to the ball then (it stops within 0.25 m by its own
  *     estimate).
  */
object FollowerBench extends Benchmark {
  val name = "follower"

  private val Ball = Scene(0.5, 0.3)

  def run(): ListMap[String, Double] = GatewayBench.quietLogging {
    val e2e = new EndToEndNode
    try {
      val robot = e2e.spawnRobot(16, firmware = _.copy(startPose = Pose(-1.0, 0.0, 0.0), scene = Ball))
      val online = 30.seconds.fromNow
      while (!e2e.isOnline(16) && online.hasTimeLeft()) Thread.sleep(50)
      require(e2e.isOnline(16), "robot 16 did not come online")
      val node = e2e.appNode()
      val robotInterface = e2e.connect(node, "ball-follower", 1, 30.seconds)
      val start = System.nanoTime()
      val follower = node.systemActorOf(BallFollower(robotInterface, 16), "follower-16")
      def progress(): BallFollower.Progress =
        Await.result(follower.ask(BallFollower.GetProgress.apply)(akka.util.Timeout(5.seconds), node.scheduler),
          6.seconds)
      val deadline = 90.seconds.fromNow
      var firstFrame = Double.NaN
      var reached = Double.NaN
      while (reached.isNaN && deadline.hasTimeLeft()) {
        val p = progress()
        val since = (System.nanoTime() - start) / 1e9
        if (firstFrame.isNaN && p.frames > 0) firstFrame = since
        if (p.reached) reached = since
        else Thread.sleep(50)
      }
      val pose = e2e.view(robot).pose
      ListMap(
        "follower_first_frame_s" -> firstFrame,
        "follower_reach_s" -> reached,
        "follower_final_distance_m" -> Ball.ballDistance(pose)
      )
    } finally e2e.shutdown()
  }
}
