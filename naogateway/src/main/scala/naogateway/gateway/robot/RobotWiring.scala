package naogateway.gateway.robot

import akka.actor.typed.ActorRef

import naogateway.gateway.link.{Backlog, PortProgress}
import naogateway.gateway.recording.RobotClockEstimates
import naogateway.access.RobotAccess
import naogateway.api.GatewayEvent

/** How a robot actor is wired to its gateway. With a `gateway`, the actor asks it for the subscribers on every start (a
  * restarted actor must not use the list it was spawned with) and holds its events until the answer comes; the gateway
  * pushes every later change itself. Without one, `subscribers` is the list. `backlog` counts the datagrams the robot
  * port's reader has handed the actor, given back as each is handled. `clocks` is where the actor puts the robot's
  * clock estimate at every keep-alive, for the recorder. `port` is how far the reader of the port that carries the
  * robot's datagrams has caught up, so the heartbeat does not judge the robot by answers still waiting in the socket.
  */
private[naogateway] final case class RobotWiring(subscribers: Set[ActorRef[GatewayEvent]],
    gateway: Option[ActorRef[RobotActor.SubscribersWanted]], backlog: Backlog,
    clocks: RobotClockEstimates = new RobotClockEstimates, port: PortProgress = PortProgress.Always)

/** Wirings without a gateway. */
private[naogateway] object RobotWiring {

  /** Events to `events` alone, no gateway to ask: for a robot actor on its own (tests). */
  def to(events: ActorRef[GatewayEvent]): RobotWiring = RobotWiring(Set(events), None, new Backlog(Int.MaxValue))
}

/** A robot actor as the gateway holds it: one actor seen through two protocols, its own and the middleware's
  * ([[RobotAccess]]). The actor wraps each message of the latter into its own as it arrives, in its own mailbox
  * (`Behaviors.transformMessages`), so handing `access` out adds no actor and no hop, and only `own` reaches the rest.
  */
private[naogateway] final case class RobotRef(own: ActorRef[RobotActor.Command], access: ActorRef[RobotAccess.Command])

/** The two views of one spawned robot actor. */
private[naogateway] object RobotRef {
  def apply(actor: ActorRef[Any]): RobotRef = RobotRef(actor, actor)
}

/** How a robot is reached: `RobotActor` is the same above the transport for both kinds. */
private[naogateway] sealed trait RobotTransport extends Product with Serializable

/** The two kinds of robot. */
private[naogateway] object RobotTransport {

  /** FU-Remote frames in UDP datagrams through the gateway's outbox: the CM-530. */
  case object Datagrams extends RobotTransport

  /** Serialized `Message`s to a ZeroMQ REP socket at `endpoint`: the original naogateway's robots. */
  final case class ZeroMq(endpoint: String) extends RobotTransport
}
