package apps.web

import java.net.InetSocketAddress

import scala.concurrent.Await
import scala.concurrent.duration._

import akka.actor.typed.scaladsl.AskPattern._
import akka.actor.typed.scaladsl.adapter._
import akka.actor.typed.{ActorRef, ActorSystem}
import akka.util.Timeout
import com.typesafe.config.{Config, ConfigFactory}

import naogateway.sim.{Fleet, FleetHandle, FleetSettings, SimulatedGameController, SimulatedGameControllerSettings}
import naogateway.testkit.TestLoopback
import naogateway.access.GatewayAccess
import naogateway.gateway.{Gateway, GatewayReadView, GatewaySettings}
import robotmiddleware.{MiddlewareSettings, RobotMiddleware}
import naogateway.api.GatewayAddresses

/** The demo as the web view's tests and bench see it: a gateway on loopback, its middleware, three simulated robots on
  * addresses of their own, a simulated GameController with short phases, and the web view on a free port.
  */
final class WebDemo(system: ActorSystem[_], settings: WebSettings, robots: Int = 3) {
  private implicit val timeout: Timeout = Timeout(10.seconds)
  private implicit val s: ActorSystem[_] = system
  private val name = s"web-demo-${System.nanoTime()}"

  val gateway: ActorRef[GatewayAccess.Command] =
    system.systemActorOf(Gateway(GatewaySettings(system)), s"$name-gateway")
  val middleware: ActorRef[RobotMiddleware.Command] =
    system.systemActorOf(RobotMiddleware(gateway, MiddlewareSettings(system)), s"$name-middleware")
  private val addresses = Await.result(gateway.ask[GatewayAddresses](GatewayAccess.GetAddresses(_)), 10.seconds)
  val fleet: FleetHandle = Await.result(Fleet.start(system,
      FleetSettings(addresses.robots, (1 to robots).toVector,
        firstAddress = TestLoopback.block(robots))), 60.seconds)
  private val gc = system.systemActorOf(
    SimulatedGameController(SimulatedGameControllerSettings(addresses.gameController.get,
        initial = 2.seconds, ready = 2.seconds, set = 2.seconds, playing = 6.seconds, finished = 2.seconds,
        interval = 100.millis)),
    s"$name-gc"
  )

  /** What the launcher hands the web view of this gateway. */
  val side: WebServer.GatewaySide = WebDemo.gatewaySide(gateway)(system)
  val server: ActorRef[WebServer.Command] = system.systemActorOf(WebServer(side, middleware, settings), s"$name-web")

  /** Where the web view listens. */
  val address: InetSocketAddress =
    Await.result(server.ask[Option[InetSocketAddress]](WebServer.GetAddress(_)), 10.seconds).getOrElse(
      sys.error("the web view did not bind"))

  /** The page's address, with `token` when given. */
  def page(token: Option[String] = None): String =
    s"http://127.0.0.1:${address.getPort}/" + token.fold("")(t => s"?token=$t")

  /** The WebSocket's address. */
  def ws(token: Option[String] = settings.token.headOption.map(_ => settings.token)): String =
    s"ws://127.0.0.1:${address.getPort}/ws" + token.fold("")(t => s"?token=$t")

  /** The server's connection counters. */
  def counters: WebServer.Counters = Await.result(server.ask[WebServer.Counters](WebServer.GetCounters(_)), 10.seconds)

  /** Stops everything it started. */
  def stop(): Unit = {
    system.toClassic.stop(server.toClassic)
    system.toClassic.stop(gc.toClassic)
    Await.result(fleet.stop(), 30.seconds)
    system.toClassic.stop(middleware.toClassic)
    system.toClassic.stop(gateway.toClassic)
  }
}

/** The config the web view's tests run with, and the launcher's wiring of the web view beside their own gateway. */
object WebDemo {

  /** Gateway on loopback ports of its own, no recording, the web view on a free loopback port. */
  val config: Config = ConfigFactory.parseString(
    """naogateway {
      |  link { bind-address = "127.0.0.1", robot-port = 0 }
      |  game-controller { bind-address = "127.0.0.1", port = 0, trusted-sources = ["127.0.0.0/8"] }
      |  recording.enabled = off
      |}
      |apps.web { enabled = on, port = 0, push-interval = 200ms, sample-interval = 500ms }
      |""".stripMargin).withFallback(ConfigFactory.load())

  /** What the web view reads of `gateway`, as the launcher hands it: view, competition flag, signing rules. */
  def gatewaySide(gateway: ActorRef[GatewayAccess.Query], competition: Option[Boolean] = None)(
      implicit system: ActorSystem[_]): WebServer.GatewaySide = {
    val settings = GatewaySettings(system)
    WebServer.GatewaySide(GatewayReadView(gateway, 3.seconds), competition.getOrElse(settings.competition),
      id => settings.signingOf(id).name)
  }
}
