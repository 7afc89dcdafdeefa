package robotmiddleware

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.TestInbox
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.wire.{ActuatorGroup, Posture, RpcCall, RpcValue}
import naogateway.api.{RobotFailure, RobotOffline, RobotOnline, RobotRestarted, VisionFrame}
import robotmiddleware.GuardState.{BatteryChange, SafetyStep}

/** The guard's state without actors: each named transition, and `Operation` to and from the robot's calls. */
class GuardStateSpec extends AnyWordSpec with Matchers {

  private val settings =
    MiddlewareSettings(
      lowBattery = 10.5,
      batteryOk = 11.0,
      walkRefresh = 200.millis,
      callTimeout = 1.second,
      postureTimeout = 3.seconds,
      linkStatsInterval = 1.second,
      pendingLimit = 8,
      batteryReadings = 3
    )
  private def app(name: String, priority: Int) = AppInfo(TestInbox[AppEvent](name).ref, name, priority)
  private val low = app("low", 1)
  private val high = app("high", 5)
  private val at = new InetSocketAddress("127.0.0.7", 3838)
  private val onlineState = GuardState(online = true)

  "A guard's state" should {
    "grant leases all or none, naming the first conflict in the docs' order, and say whom it preempts" in {
      val (held, none) = onlineState.acquire(low, Set(ActuatorGroup.Walk, ActuatorGroup.Head)).toOption.get
      none shouldBe empty
      held.leases shouldBe Map(ActuatorGroup.Walk -> low, ActuatorGroup.Head -> low)
      // An equal or lower priority takes nothing, not even the free group it asked for as well.
      held.acquire(app("other", 1), Set(ActuatorGroup.Speech, ActuatorGroup.Head, ActuatorGroup.Walk)) shouldBe
        Left(ActuatorGroup.Walk -> low)
      val (taken, preempted) = held.acquire(high, Set(ActuatorGroup.Head, ActuatorGroup.Speech)).toOption.get
      preempted shouldBe Vector(ActuatorGroup.Head -> low)
      taken.leases shouldBe Map(ActuatorGroup.Walk -> low, ActuatorGroup.Head -> high, ActuatorGroup.Speech -> high)
      taken.holds(7).leases shouldBe Map(ActuatorGroup.Walk -> "low", ActuatorGroup.Head -> "high",
        ActuatorGroup.Speech -> "high")
    }

    "release only what the app holds, and free everything of an app that is gone" in {
      val (held, _) = onlineState.acquire(low, Set(ActuatorGroup.Walk, ActuatorGroup.Arms)).toOption.get
      held.release(high.events, ActuatorGroup.Walk) shouldBe None
      held.release(low.events, ActuatorGroup.Walk).map(_.leases.keySet) shouldBe Some(Set(ActuatorGroup.Arms))
      val (gone, groups) = held.appGone(low.events)
      groups shouldBe Set(ActuatorGroup.Walk, ActuatorGroup.Arms)
      gone.leases shouldBe empty
      held.appGone(high.events)._2 shouldBe empty
    }

    "refuse an operation out of range, offline, without its lease, or moving under a safety hold, in that order" in {
      val (held, _) = onlineState.acquire(low, Set(ActuatorGroup.Walk)).toOption.get
      val walk = Operation.Walk(0.1, 0, 0)
      held.refusal(7, low, walk, settings.limits) shouldBe None
      held.refusal(7, low, Operation.Walk(100, 0, 0), settings.limits).get shouldBe a[RobotFailure.RobotError]
      held.copy(online = false).refusal(7, low, walk, settings.limits) shouldBe Some(RobotFailure.RobotOffline(7))
      held.refusal(7, high, walk, settings.limits) shouldBe
        Some(RobotFailure.LeaseNotHeld(7, ActuatorGroup.Walk, Some("low")))
      held.refusal(7, high, Operation.RawCall("system", "battery", Vector.empty), settings.limits) shouldBe None
      val hold = held.copy(safety = Some("battery low"))
      hold.refusal(7, low, walk, settings.limits) shouldBe Some(RobotFailure.SafetyHold(7, "battery low"))
      hold.refusal(7, low, Operation.Stop(), settings.limits) shouldBe None
      hold.refusal(7, low, Operation.Posture(Posture.Sit), settings.limits) shouldBe None
      hold.refusal(7, low, Operation.Posture(Posture.Stand), settings.limits) shouldBe
        Some(RobotFailure.SafetyHold(7, "battery low"))
      hold.refusal(7, low, Operation.RawCall("motion", "posture", Vector(RpcValue.Text("sit"))),
        settings.limits) shouldBe
        None
    }

    "forget the walk when the robot goes offline, and stop a robot only when it really came back" in {
      val walking = onlineState.walkStarted(Operation.Walk(0.1, 0, 0), low)
      val offline = walking.eventReceived(RobotOffline(7, "quiet"))
      offline.walking shouldBe None
      offline.online shouldBe false
      offline.eventWhileReady(RobotOnline(7, at))._2 shouldBe true
      // An online event older than the snapshot (the robot never was offline to the guard) stops nothing.
      onlineState.eventWhileReady(RobotOnline(7, at))._2 shouldBe false
      onlineState.eventWhileReady(RobotRestarted(7, Some(1), Vector.empty)) shouldBe (onlineState -> false)
    }

    "owe a reconnect stop for a robot that came back while connecting, and not for one offline again" in {
      val back = GuardState().eventWhileConnecting(RobotOnline(7, at))
      back.reconnectedWhileConnecting shouldBe true
      back.reconnectStopped.reconnectedWhileConnecting shouldBe false
      back.eventWhileConnecting(RobotOffline(7, "quiet")).reconnectedWhileConnecting shouldBe false
      onlineState.eventWhileConnecting(RobotOnline(7, at)).reconnectedWhileConnecting shouldBe false
    }

    "refresh a walk only once the robot confirmed it, and forget a refused one" in {
      val w = Operation.Walk(0.2, 0, 0)
      val walking = onlineState.walkStarted(w, low)
      walking.walkAnswered(w, confirmed = true) shouldBe Some(walking -> true)
      walking.walkAnswered(w, confirmed = false) shouldBe Some(walking.walkEnded -> false)
      walking.walkAnswered(Operation.Walk(0.3, 0, 0), confirmed = true) shouldBe None
      walking.walkEnded.walking shouldBe None
    }

    "keep one safety stop in flight, and sit after it when a hold wanted the robot sitting meanwhile" in {
      val (first, now) = onlineState.safetyStep(SafetyStep.StopOnly)
      now shouldBe true
      val (second, again) = first.safetyStep(SafetyStep.StopAfterReconnect)
      again shouldBe false
      second shouldBe first
      val (held, later) = first.copy(safety = Some("battery low")).safetyStep(SafetyStep.StopThenSit)
      later shouldBe false
      held.sitAfterStop shouldBe true
      val (done, sit) = held.safetyStepDone(SafetyStep.StopOnly)
      sit shouldBe true
      done.stopInFlight shouldBe false
      done.sitAfterStop shouldBe false
      // A sit is never held back, and a stop answered once the hold has ended sits nobody.
      done.safetyStep(SafetyStep.Sit) shouldBe (done -> true)
      held.copy(safety = None).safetyStepDone(SafetyStep.StopThenSit)._2 shouldBe false
    }

    "start a battery hold on sustained low readings only, and clear it on sustained good ones" in {
      val (s1, c1) = onlineState.batteryRead(10.0, settings)
      val (s2, c2) = s1.batteryRead(10.2, settings)
      c1 shouldBe None
      c2 shouldBe None
      val (s3, c3) = s2.batteryRead(10.1, settings)
      c3 shouldBe Some(BatteryChange.HoldStarted(GuardState.batteryLow(10.2, 3, settings)))
      s3.safety shouldBe Some(GuardState.batteryLow(10.2, 3, settings))
      val (s4, c4) = s3.batteryRead(11.5, settings)._1.batteryRead(11.5, settings)
      c4 shouldBe None
      val (s5, c5) = s4.batteryRead(10.9, settings)
      c5 shouldBe None // not all three above battery-ok
      val (s6, _) = s5.batteryRead(11.2, settings)
      val (s7, c7) = s6.batteryRead(11.3, settings)
      c7 shouldBe None // 10.9 is still among the last three
      val (s8, c8) = s7.batteryRead(11.4, settings)
      c8 shouldBe Some(BatteryChange.HoldCleared)
      s8.safety shouldBe None
      s8.readings shouldBe Vector(11.2, 11.3, 11.4)
    }

    "hold the apps' camera and link-figure watchers, saying which camera watcher is new" in {
      val camera = TestInbox[VisionFrame]().ref
      val (s1, fresh) = onlineState.visionWatched(camera, grid = false)
      fresh shouldBe true
      val (s2, again) = s1.visionWatched(camera, grid = true)
      again shouldBe false
      s2.visionWatchers shouldBe Map(camera -> true)
      s2.visionGone(camera).visionWatchers shouldBe empty
      val stats = TestInbox[naogateway.api.LinkStats]().ref
      onlineState.statsWatched(stats).statsGone(stats).statsWatchers shouldBe empty
    }
  }

  "An operation" should {
    "become the robot call the method table names, and be read back from it" in {
      val ops = Vector(
        Operation.Walk(0.25, -0.5, 1.0),
        Operation.Stop(),
        Operation.Head(0.5, -0.25),
        Operation.Arms(0.5, 1.0, -0.5, -1.0),
        Operation.Posture(Posture.Crouch),
        Operation.Say("hello"),
        Operation.RawCall("system", "battery", Vector.empty)
      )
      ops.map(Operation.toCall).map(_.name) shouldBe
        Vector("motion.walk", "motion.stop", "motion.head", "motion.arms", "motion.posture", "speech.say",
          "system.battery")
      ops.foreach(op => Operation.fromCall(Operation.toCall(op)) shouldBe Right(op))
    }

    "say why a known method's parameters cannot be right" in {
      Operation.fromCall(RpcCall("motion", "walk", Vector(RpcValue.Number(1f)))) shouldBe
        Left("motion.walk takes 3 number(s) (vx, vy, omega), got (number)")
      Operation.fromCall(RpcCall("motion", "stop", Vector(RpcValue.Text("now")))) shouldBe
        Left("motion.stop takes no parameters, got (text)")
      Operation.fromCall(RpcCall("motion", "head", Vector(RpcValue.Number(Float.NaN), RpcValue.Number(0f)))) shouldBe
        Left("motion.head: numbers must be finite")
      Operation.fromCall(RpcCall("speech", "say", Vector.empty)) shouldBe Left("speech.say takes one text, got none")
      Operation.fromCall(RpcCall("motion", "posture", Vector(RpcValue.Text("fly")))).isLeft shouldBe true
      Operation.fromCall(RpcCall("motion", "dance", Vector(RpcValue.UInt(3)))) shouldBe
        Right(Operation.RawCall("motion", "dance", Vector(RpcValue.UInt(3))))
    }
  }
}
