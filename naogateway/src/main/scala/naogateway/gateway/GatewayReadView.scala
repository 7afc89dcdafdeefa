package naogateway.gateway

import scala.concurrent.Future
import scala.concurrent.duration.FiniteDuration

import akka.actor.typed.scaladsl.AskPattern._
import akka.actor.typed.{ActorRef, ActorSystem}
import akka.util.Timeout

import naogateway.wire.gamecontroller.GameControlData
import naogateway.access.GatewayAccess
import naogateway.api.recording.GatewayTap
import naogateway.api.{GameSource, GatewayAddresses, GatewayStats, GatewayView, RobotLinks, RobotSnapshot, TrafficStats}

/** The gateway's side of [[GatewayView]] (api): each question asked of the gateway actor's read-only queries. */
object GatewayReadView {

  /** A view of `gateway` whose every question fails when the gateway has not answered within `timeout`. */
  def apply(gateway: ActorRef[GatewayAccess.Query], timeout: FiniteDuration)(
      implicit system: ActorSystem[_]): GatewayView =
    new GatewayView {
      private implicit val askTimeout: Timeout = timeout
      def addresses(): Future[GatewayAddresses] = gateway.ask(GatewayAccess.GetAddresses(_))
      def robots(): Future[Vector[RobotSnapshot]] = gateway.ask(GatewayAccess.GetRobots(_))
      def links(): Future[RobotLinks] = gateway.ask(GatewayAccess.GetLinkStats(_))
      def stats(): Future[GatewayStats] = gateway.ask(GatewayAccess.GetStats(_))
      def traffic(): Future[TrafficStats] = gateway.ask(GatewayAccess.GetTraffic(_))
      def gameState(): Future[Option[GameControlData]] = gateway.ask(GatewayAccess.GetGameState(_))
      def gameSource(): Future[GameSource] = gateway.ask(GatewayAccess.GetGameSource(_))
      override def tap(): Future[GatewayTap] = gateway.ask(GatewayAccess.GetTap(_))
    }
}
