package naogateway.launcher

import java.net.InetSocketAddress
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._
import scala.concurrent.{Await, Promise}

import akka.actor.typed.{ActorRef, ActorSystem, Behavior}
import akka.actor.typed.scaladsl.Behaviors
import com.typesafe.config.ConfigFactory
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.testkit.TestLoopback
import robotmiddleware.RobotMiddleware

/** The launcher's gateway node when its gateway or its middleware stops: it says which, and stops rather than hang. */
class LauncherWatchSpec extends AnyWordSpec with Matchers {

  /** The launcher's config on `robots` (the gateway's robot port), with nothing else listening: no cluster, no views.
    */
  private def config(robots: InetSocketAddress) = Launcher.nodeConfig(
    ConfigFactory.parseString(
      s"""akka.actor.provider = local
       |akka.loglevel = WARNING
       |apps.launcher { simulated-robots = 0, ball-follower-robot = 0, game-controller = off, view = lines, refresh = 10s }
       |apps.zeromq.enabled = off
       |apps.datagram-door.enabled = off
       |apps.web.enabled = off
       |apps.control.enabled = off
       |naogateway.recording.enabled = off
       |naogateway.game-controller.enabled = off
       |naogateway.link { bind-address = "${robots.getAddress.getHostAddress}", robot-port = ${robots.getPort} }
       |""".stripMargin),
    ConfigFactory.empty()
  )

  /** The root `start` makes, on `robots`: the part it says stopped (if any, in time), and whether the node stopped. */
  private def run(robots: InetSocketAddress)(start: (
          String => Unit) => Behavior[Launcher.Command]): (Option[String], Boolean) = {
    val said = Promise[String]()
    val node = ActorSystem(start(part => said.trySuccess(part)), "launcher-watch", config(robots))
    try {
      val part = scala.util.Try(Await.result(said.future, 20.seconds)).toOption
      val stopped = scala.util.Try(Await.ready(node.whenTerminated, 20.seconds)).isSuccess
      (part, stopped)
    } finally node.terminate()
  }

  "The launcher" should {
    "say the gateway stopped, and stop, when the gateway cannot have its robot port" in {
      val address = TestLoopback.address(0)
      val taken = DatagramChannel.open().bind(new InetSocketAddress(address, 0))
      try {
        val robots = taken.getLocalAddress.asInstanceOf[InetSocketAddress]
        run(robots)(stopped => Launcher.Root(stopped = stopped)) shouldBe ((Some("gateway"), true))
      } finally taken.close()
    }

    "say the middleware stopped, and stop, when the middleware fails" in {
      val robots = new InetSocketAddress(TestLoopback.address(0), 0)
      val failing = (_: ActorRef[naogateway.access.GatewayAccess.Command]) =>
        Behaviors.setup[RobotMiddleware.Command](_ => throw new IllegalStateException("the middleware's test failure"))
      run(robots)(stopped => Launcher.Root(stopped = stopped, makeMiddleware = failing)) shouldBe ((Some("middleware"),
        true))
    }

    "stay up while both run" in {
      val robots = new InetSocketAddress(TestLoopback.address(0), 0)
      val said = Promise[String]()
      val node = ActorSystem(Launcher.Root(stopped = part => said.trySuccess(part)), "launcher-watch", config(robots))
      try {
        Thread.sleep(1500)
        said.isCompleted shouldBe false
        node.whenTerminated.isCompleted shouldBe false
      } finally node.terminate()
      Await.ready(node.whenTerminated, 20.seconds)
      // A shutdown stops both parts: that is no failure to report.
      said.isCompleted shouldBe false
    }
  }
}
