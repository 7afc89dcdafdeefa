package naogateway.api

import scala.concurrent.Future

import naogateway.api.recording.GatewayTap
import naogateway.wire.gamecontroller.GameControlData

/** What apps may read of a running gateway (the status view, the web view, the control port): questions that change
  * nothing, answered later with plain data. The launcher hands apps one, built over the gateway's read-only queries; an
  * app holding it can look but never reach a robot past the middleware. A question the gateway does not answer in time
  * fails its future.
  */
trait GatewayView {

  /** Where the gateway listens (the real ports when 0 was configured). */
  def addresses(): Future[GatewayAddresses]

  /** Every known robot's snapshot. */
  def robots(): Future[Vector[RobotSnapshot]]

  /** Every known robot's link figures. */
  def links(): Future[RobotLinks]

  /** The gateway's own figures: frames in, refusals by kind and source. */
  def stats(): Future[GatewayStats]

  /** The team traffic figures and the competition gate. */
  def traffic(): Future[TrafficStats]

  /** The latest GameController packet, if any arrived. */
  def gameState(): Future[Option[GameControlData]]

  /** Where game state comes from: the trusted sources, the last sender and the packets ignored. */
  def gameSource(): Future[GameSource]

  /** The gateway's tap, to read what crosses its ports (datagrams and decisions) as the recorder does; reading changes
    * nothing the gateway does. A view without one (a stand-in in a test) fails.
    */
  def tap(): Future[GatewayTap] = Future.failed(new UnsupportedOperationException("this view has no tap"))
}
