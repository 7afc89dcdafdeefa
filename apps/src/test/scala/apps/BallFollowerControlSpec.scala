package apps

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.sim.{Pose, Scene}

class BallFollowerControlSpec extends AnyWordSpec with Matchers {

  /** Closed loop in simulated time: the simulated robot's own camera geometry and motion model, 60 ms per frame. */
  private def follow(start: Pose, scene: Scene, maxSeconds: Double): (Pose, Double, Boolean) = {
    var pose = start
    var state = BallFollowerControl.initial
    var t = 0.0
    val dt = 0.06
    while (t < maxSeconds && !state.reached) {
      val regions = Scene.regions(scene, pose, state.pan, state.tilt)
      val (next, targets) = BallFollowerControl.step(state, regions)
      state = next
      pose = pose.moved(math.min(targets.vx, 0.3), 0.0, math.max(-1.0, math.min(1.0, targets.omega)), dt)
      t += dt
    }
    (pose, t, state.reached)
  }

  "The ball follower's control law" should {
    "estimate the ball's bearing and distance from one region" in {
      val scene = Scene(1.5, 0.0)
      val ball = Scene.regions(scene, Pose(0, 0, 0), 0.0, -0.3).find(_.colour == Scene.BallColour).get
      val (bearing, distance) = BallFollowerControl.locate(ball, 0.0, -0.3)
      bearing shouldBe 0.0 +- 0.05
      distance shouldBe 1.5 +- 0.3
    }
    "reach a ball ahead within a bounded simulated time" in {
      val scene = Scene(0.5, 0.3)
      val (pose, seconds, reached) = follow(Pose(-1.0, 0.0, 0.0), scene, maxSeconds = 30)
      reached shouldBe true
      scene.ballDistance(pose) should be < 0.45
      seconds should be < 20.0
    }
    "find and reach a ball behind the robot" in {
      val scene = Scene(-2.0, 1.0)
      val (pose, _, reached) = follow(Pose(0.0, 0.0, 0.0), scene, maxSeconds = 60)
      reached shouldBe true
      scene.ballDistance(pose) should be < 0.45
    }
  }
}
