package apps

import java.net.{DatagramSocket, InetSocketAddress}
import java.util.concurrent.{ConcurrentLinkedQueue, TimeUnit}

import scala.concurrent.duration._
import scala.concurrent.{Await, Future}
import scala.jdk.CollectionConverters._
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.{ActorTestKit, TestProbe}
import akka.actor.typed.ActorRef

import naogateway.wire.ActuatorGroup
import naogateway.integration.{GatewayInternals, TestStream}
import naogateway.access.GatewayAccess
import naogateway.api.{GatewayAddresses, RobotFailure}
import naogateway.gateway.{Gateway, GatewaySettings}
import naogateway.gateway.robot.StreamActor
import robotmiddleware.{MiddlewareSettings, RobotClient, RobotInterface, RobotMiddleware}

/** A gateway and a middleware as the test kit's configuration sets them, one client of the middleware, and the steps
  * every spec that drives a robot through them takes: wait until the robot is online, acquire it, reach its stream.
  * Shared by the specs of the firmware's robots (posix and qemu) and of the conformance robot; each part starts when
  * first used, so a spec cancelled before (a missing tool) starts nothing. What the spec starts beside (robot
  * processes, sockets, boards) it hands the rig, which ends it all in [[close]], from the spec's `afterAll`.
  */
final class RobotRig(kit: ActorTestKit, clientName: String, connectWithin: FiniteDuration = 15.seconds) {

  private val cleanups = new ConcurrentLinkedQueue[() => Unit]()

  /** Runs `cleanup` in [[close]], after those registered before it. */
  def onClose(cleanup: => Unit): Unit = {
    cleanups.add(() => cleanup)
    ()
  }

  /** `p`, destroyed in [[close]] (forcibly when it has not ended `grace` later). */
  def owned(p: Process, grace: FiniteDuration): Process = {
    onClose {
      p.destroy()
      if (!p.waitFor(grace.toMillis, TimeUnit.MILLISECONDS)) { p.destroyForcibly(); () }
    }
    p
  }

  /** `s`, closed in [[close]]. */
  def owned(s: DatagramSocket): DatagramSocket = {
    onClose(s.close())
    s
  }

  /** Ends everything handed to the rig, each clean-up whatever the others did; for the spec's `afterAll`, before the
    * kit shuts down.
    */
  def close(): Unit = cleanups.asScala.foreach(c => Try(c()))

  /** The gateway, spawned as `gateway`. */
  lazy val gateway: ActorRef[GatewayAccess.Command] = kit.spawn(Gateway(GatewaySettings(kit.system)), "gateway")

  /** The middleware over the gateway, spawned as `middleware`. */
  lazy val middleware: ActorRef[RobotMiddleware.Command] =
    kit.spawn(RobotMiddleware(gateway, MiddlewareSettings(kit.system)), "middleware")

  /** Where the gateway receives the robots' datagrams. */
  lazy val gatewayAddress: InetSocketAddress = {
    val probe = kit.createTestProbe[GatewayAddresses]()
    gateway ! GatewayAccess.GetAddresses(probe.ref)
    probe.receiveMessage(10.seconds).robots
  }

  /** Starts the gateway and the middleware now rather than on first use: the middleware and where the gateway receives
    * the robots' datagrams.
    */
  def start(): (ActorRef[RobotMiddleware.Command], InetSocketAddress) = (middleware, gatewayAddress)

  /** The client every call of the spec goes through (priority 5). */
  lazy val client: RobotInterface =
    Await.result(RobotClient.connect(kit.system, middleware, clientName, priority = 5), connectWithin)

  /** Whether the middleware lists robot `id` as online now. */
  def isOnline(id: Int): Boolean =
    Try(Await.result(client.robots(), 5.seconds)).toOption.exists(_.exists(r => r.robotId == id && r.online))

  /** Waits at most `within` for robot `id` to come online, asking every `every`; whether it did. */
  def awaitOnline(id: Int, within: FiniteDuration, every: FiniteDuration = 50.millis): Boolean =
    RobotCalls.poll(within, every)(isOnline(id))

  /** Acquires every actuator group of robot `id` for the client; throws what the acquire failed with. */
  def acquireAll(id: Int, within: FiniteDuration): Unit = {
    Await.result(client.acquire(id, ActuatorGroup.all.toSeq: _*), within)
    ()
  }

  /** The gateway's stream endpoint for robot `id`, subscribed to what it delivers; `None` when the gateway does not
    * know the robot.
    */
  def streamOf(id: Int): Option[(TestStream, TestProbe[StreamActor.Received])] =
    GatewayInternals.stream(gateway, id)(kit.system).map { stream =>
      val received = kit.createTestProbe[StreamActor.Received]()
      stream.subscribe(received.ref)
      stream -> received
    }
}

/** Waiting and call results for the specs that drive a robot through the middleware. */
object RobotCalls {

  /** Polls `condition` every `every` until it holds or `within` has passed; whether it held. */
  def poll(within: FiniteDuration, every: FiniteDuration = 50.millis)(condition: => Boolean): Boolean = {
    val deadline = within.fromNow
    var ok = condition
    while (!ok && deadline.hasTimeLeft()) { Thread.sleep(every.toMillis); ok = condition }
    ok
  }

  /** The call's outcome, waiting at most `within`. */
  def result[T](f: Future[T], within: FiniteDuration = 15.seconds): Either[Throwable, T] =
    Try(Await.result(f, within)).toEither

  /** The robot's error text of a failed call, or a text saying the outcome was something else. */
  def robotError(r: Either[Throwable, _]): String = r match {
    case Left(RobotFailure.RobotError(_, e)) => e
    case other                               => s"not a robot error: $other"
  }
}
