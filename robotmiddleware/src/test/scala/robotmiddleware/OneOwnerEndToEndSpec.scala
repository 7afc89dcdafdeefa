package robotmiddleware

import naogateway.wire.ActuatorGroup

import scala.concurrent.duration._
import scala.concurrent.{Await, Future}
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.actor.typed.ActorRef
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.testkit.TestLoopback
import naogateway.access.RobotAccess
import naogateway.api.{CallResult, RobotOnline, VisionFrame}
import naogateway.integration.GatewayFixture
import naogateway.sim.network.{Impairment, LossyNetwork}
import naogateway.sim.{ReceivedCall, SimulatedRobot}
import naogateway.wire.{Posture, RpcMethod, RpcValue}

/** A robot's command order end to end, seen where it counts: the simulated robot's receive log. Loopback only, ports
  * chosen by the system; generous timeouts, no timed assertions.
  */
class OneOwnerEndToEndSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {
  private val settings = MiddlewareSettings(10.8, 11.0, 200.millis, 2.seconds, 5.seconds, 1.second, 64)
  private val Patience = 30.seconds

  /** Tries `op` until it succeeds (a call may be lost on a lossy link three times over), at most `tries` times. */
  private def untilDone[T](tries: Int)(op: => Future[T]): T = {
    var last: Try[T] = Try(throw new IllegalStateException("not tried"))
    var left = tries
    while (left > 0 && last.isFailure) {
      last = Try(Await.result(op, Patience))
      left -= 1
    }
    last.get
  }

  private def received(robot: ActorRef[SimulatedRobot.Command]): Vector[ReceivedCall] = {
    val probe = createTestProbe[Vector[ReceivedCall]]()
    robot ! SimulatedRobot.GetReceivedCalls(probe.ref)
    probe.receiveMessage(10.seconds)
  }

  private def numbers(params: Vector[RpcValue]): Vector[Float] = params.collect { case RpcValue.Number(v) => v }

  "A robot's commands" must {
    "never let a walk reach the robot after the stop, and let head and arms converge to the latest target, under loss and a full budget" in {
      val f = new GatewayFixture(testKit, "budget.team-bytes-per-second = 1400")
      val network = LossyNetwork.start(seed = 11)
      try {
        val lossy = Impairment(loss = 0.1)
        val proxy = network.addProxy(f.addresses.robots, TestLoopback.address(), uplink = lossy, downlink = lossy)
        val (robot, _) = f.robot(21, to = proxy.clientSide)
        f.awaitEvent(Patience) { case RobotOnline(21, _) => () }
        val middleware = spawn(RobotMiddleware(f.gateway, settings))
        val app = Await.result(RobotClient.connect(system, middleware, "walker", 1), Patience)
        untilDone(5)(app.acquire(21, ActuatorGroup.Walk, ActuatorGroup.Head, ActuatorGroup.Arms))
        untilDone(10)(app.posture(21, Posture.Stand)) shouldBe Posture.Stand
        untilDone(10)(app.walk(21, 0.2, 0, 0))
        // Quick changes of every slot: far more than the budget lets out, so the outbox holds them back.
        val burst = (1 to 40).flatMap { i =>
          Seq(app.head(21, i * 0.01, 0), app.arms(21, i * 0.01, 0, 0, 0)) ++
            (if (i % 10 == 0) Seq(app.walk(21, 0.1 + i * 0.001, 0, 0)) else Nil)
        }
        eventually(timeout(10.seconds)) { f.traffic().queued.values.sum should be > 0 }
        untilDone(10)(app.stop(21))
        val (pan, shoulder) = (0.45, 0.55)
        untilDone(10)(app.head(21, pan, 0))
        untilDone(10)(app.arms(21, shoulder, 0, 0, 0))
        burst.foreach(b => Try(Await.ready(b, Patience)))
        // Longer than a call's retries take: anything still on its way would have arrived.
        Thread.sleep(3000)
        val log = received(robot).map(_.call)
        val firstWalk = log.indexWhere(c => RpcMethod.of(c).contains(RpcMethod.Walk))
        firstWalk should be >= 0
        val firstStop = log.indexWhere(c => RpcMethod.of(c).contains(RpcMethod.Stop), firstWalk)
        firstStop should be > firstWalk
        withClue(log.drop(firstStop).map(_.name).mkString(", ")) {
          log.drop(firstStop).exists(c => RpcMethod.of(c).contains(RpcMethod.Walk)) shouldBe false
        }
        numbers(log.filter(c => RpcMethod.of(c).contains(RpcMethod.Head)).last.params) shouldBe Vector(pan.toFloat, 0f)
        numbers(log.filter(c => RpcMethod.of(c).contains(RpcMethod.Arms)).last.params) shouldBe Vector(shoulder.toFloat,
          0f, 0f, 0f)
        f.view(robot).head shouldBe ((pan.toFloat.toDouble, 0.0))
        app.close()
      } finally {
        network.stop()
        f.stop()
      }
    }

    "keep an app's calls and camera stream working through a restart of the robot actor and of each child it hands out" in {
      val f = new GatewayFixture(testKit)
      try {
        val (robot, _) = f.robot(22)
        f.awaitEvent(Patience) { case RobotOnline(22, _) => () }
        val middleware = spawn(RobotMiddleware(f.gateway, settings))
        val app = Await.result(RobotClient.connect(system, middleware, "looker", 1), Patience)
        untilDone(5)(app.acquire(22, ActuatorGroup.Head))
        // One camera stream for the whole test; each step watches it through a probe of its own, so frames from
        // before a crash cannot count for after it.
        val watcher = new java.util.concurrent.atomic.AtomicReference(createTestProbe[VisionFrame]())
        app.vision(22).runForeach(frame => watcher.get.ref ! frame)
        watcher.get.expectMessageType[VisionFrame](Patience)
        var pan = 0.0
        // Supervisors' failure reports, counted at the root logger: proof that each crash below really happened.
        val failures = new java.util.concurrent.atomic.AtomicInteger()
        val root = org.slf4j.LoggerFactory.getLogger(org.slf4j.Logger.ROOT_LOGGER_NAME).asInstanceOf[
          ch.qos.logback.classic.Logger]
        val counter = new ch.qos.logback.core.AppenderBase[ch.qos.logback.classic.spi.ILoggingEvent] {
          override def append(e: ch.qos.logback.classic.spi.ILoggingEvent): Unit =
            if (e.getLevel == ch.qos.logback.classic.Level.ERROR && e.getFormattedMessage.contains("saw failure"))
              failures.incrementAndGet()
        }
        counter.start()
        root.addAppender(counter)
        // The app still moves the robot's head and still gets camera frames after `crash` made an actor fail.
        def stillWorks(what: String)(crash: => Unit): Unit = withClue(what) {
          val before = failures.get
          crash
          pan += 0.1
          eventually(timeout(Patience)) {
            Await.result(app.head(22, pan, 0), 10.seconds)
            f.view(robot).head._1 shouldBe (pan.toFloat.toDouble +- 1e-6)
          }
          watcher.set(createTestProbe[VisionFrame]())
          watcher.get.expectMessageType[VisionFrame](Patience)
          // The actor did fail (some only on the call after the crash message): one report per crash.
          eventually(timeout(Patience)) { failures.get shouldBe before + 1 }
        }
        // A reply ref or route that is null stands in for any bug: the actor throws and its supervisor restarts it.
        stillWorks("robot actor")(f.robotAccess(22) ! RobotAccess.GetSnapshot(null))
        stillWorks("response actor")(f.open(22).response ! RobotAccess.Call(null, createTestProbe[CallResult]().ref))
        stillWorks("vision actor")(f.crashVision(22))
        stillWorks("stream actor")(f.crashStream(22))
        // The sender hands a caller's send to the response actor for its call id: a null call fails there, once.
        stillWorks("no-response actor")(f.crashSender(22))
        app.close()
        root.detachAppender(counter)
      } finally f.stop()
    }
  }
}
