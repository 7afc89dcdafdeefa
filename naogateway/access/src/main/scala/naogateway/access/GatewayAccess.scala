package naogateway.access

import akka.actor.typed.ActorRef

import naogateway.wire.gamecontroller.GameControlData
import naogateway.api.recording.GatewayTap
import naogateway.api.{
  GameSource,
  GatewayAddresses,
  GatewayEvent,
  GatewayStats,
  RobotLinks,
  RobotSnapshot,
  TrafficStats
}

/** What may be sent to the gateway from outside it: the middleware may send all of it, operator tools (the status view,
  * the control port, the doctor) the read-only [[GatewayAccess.Query]] part. Nothing here feeds the gateway frames or
  * reaches a robot's sender; a robot is reached only through its [[RobotAccess]].
  *
  * Why a module of its own (`access`, on the api and akka-actor-typed only): the middleware compiles against this
  * protocol and not against the gateway, so no gateway internal can creep into it (robotmiddleware's
  * MiddlewareLayerSpec shows scalac refusing one). The gateway implements it without an extra actor: its actors are
  * spawned with `Behaviors.transformMessages`, which wraps each message of this protocol into a `private[naogateway]`
  * command of the receiving actor as it arrives, in that actor's own mailbox (no forwarding actor, no extra hop on the
  * call path). The actors' own sealed `Command`s stay `private[naogateway]` in what they carry and their handling stays
  * total; the spawner holds one ref with two typed views, the actor's own protocol and this one (docs/architecture.md,
  * "The access protocol").
  */
object GatewayAccess {

  /** What the middleware may send the gateway. `RobotMiddleware` takes an `ActorRef[GatewayAccess.Command]`. */
  sealed trait Command

  /** The read-only part: questions that change nothing. Operator tools hold an `ActorRef[GatewayAccess.Query]`, so they
    * can look but never reach a robot past the middleware.
    */
  sealed trait Query extends Command

  /** Answers with the bound addresses (the real ports when 0 was configured). */
  final case class GetAddresses(replyTo: ActorRef[GatewayAddresses]) extends Query

  /** Answers with every known robot's snapshot, asked of the robot actors (`snapshot-timeout` for each). */
  final case class GetRobots(replyTo: ActorRef[Vector[RobotSnapshot]]) extends Query

  /** Answers with every known robot's link figures, asked of the robot actors (`snapshot-timeout` for each). */
  final case class GetLinkStats(replyTo: ActorRef[RobotLinks]) extends Query

  /** Answers with the gateway's own figures. */
  final case class GetStats(replyTo: ActorRef[GatewayStats]) extends Query

  /** Answers with the team traffic figures of the outbox. */
  final case class GetTraffic(replyTo: ActorRef[TrafficStats]) extends Query

  /** Answers with the latest GameController packet, if any arrived. */
  final case class GetGameState(replyTo: ActorRef[Option[GameControlData]]) extends Query

  /** Answers with where game state comes from: the trusted sources, the last sender and the packets ignored. */
  final case class GetGameSource(replyTo: ActorRef[GameSource]) extends Query

  /** Answers with the gateway's tap, to subscribe to what crosses its ports (the live feed). Changes nothing;
    * JVM-local: the tap is an object of this process, never sent over the wire.
    */
  final case class GetTap(replyTo: ActorRef[GatewayTap]) extends Query

  /** Answers with the robot `robotId` as the middleware may use it ([[RobotAccess]]), if the robot is known. */
  final case class GetRobotAccess(robotId: Int, replyTo: ActorRef[Option[ActorRef[RobotAccess.Command]]])
      extends Command

  /** Sends every `GatewayEvent` to `subscriber` until it stops (robot events come straight from the robot actors). */
  final case class Subscribe(subscriber: ActorRef[GatewayEvent]) extends Command

  /** Stops sending events to `subscriber`. */
  final case class Unsubscribe(subscriber: ActorRef[GatewayEvent]) extends Command
}
