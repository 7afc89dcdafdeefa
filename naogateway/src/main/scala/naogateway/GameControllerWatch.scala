package naogateway

import java.net.InetSocketAddress

import akka.actor.typed.ActorRef
import akka.actor.typed.scaladsl.{ActorContext, Behaviors}

import naogateway.link.UdpLink
import naogateway.wire.Datagram
import naogateway.wire.gamecontroller.{GameControlData, GameControlVersion, GameControllerCodec}

/** The gateway's GameController side, run inside the gateway actor (its state is the gateway's, touched only from its
  * messages): which packets count and from whom, the game state they give, the gates they set, the team's message
  * budget and, in the monitor role, the true game state and the robots' forwarded status messages.
  *
  * @param gate
  *   tells every gate (the outbox's, each ZeroMQ robot's) a reading
  * @param publish
  *   tells the gateway's subscribers an event
  */
private[naogateway] final class GameControllerWatch(
    settings: GatewaySettings,
    context: ActorContext[Gateway.Command],
    rejections: RejectionLedger.Shared,
    gate: GameReading => Unit,
    publish: GatewayEvent => Unit
) {
  private var packets = 0L
  private var game: Option[GameControlData] = None
  private var gameFrom: Option[InetSocketAddress] = None
  private var untrusted = 0L
  private var lastUnreadable: Option[(Long, String)] = None
  private var sources = GameControllerSources()
  private var trueStateAt: Option[Long] = None
  private var forwarded = ForwardedStatuses()
  private var budget = MessageBudget(settings.teamMessages)

  /** Control packets that counted (for `GatewayStats.gameControllerPackets`). */
  def packetsCounted: Long = packets

  /** The latest game state that counted, if any. */
  def state: Option[GameControlData] = game

  /** Where game state comes from, as `GetGameSource` answers. */
  def source(now: Long): Gateway.GameSource =
    Gateway.GameSource(
      settings.gameControllerTrusted.describe,
      gameFrom,
      untrusted,
      Option.when(settings.teamMessages.enabled)(budget.describe(now)),
      sources.warnings(now) ++ (if (settings.teamMessages.enabled) budget.warnings(now) else Vector.empty),
      trueStateAt.map(at => (now - at) / 1000000L),
      forwarded.sorted
    )

  /** The monitor role: the request for the true state, from the GameController socket, now and every request-interval
    * (a child owns the timer); the forwarded status messages on a socket of their own.
    */
  def startMonitor(gcLink: ActorRef[UdpLink.Command], m: MonitorSettings): Unit = {
    context.log.info("Gateway monitoring the GameController at {}: asking for the true game state every {}",
      m.gameController,
      m.requestInterval)
    context.spawn(
      Behaviors.withTimers[String] { timers =>
        gcLink ! UdpLink.Send(GameControllerCodec.monitorRequest, m.gameController)
        timers.startTimerWithFixedDelay("request", m.requestInterval)
        Behaviors.receiveMessage { _ =>
          gcLink ! UdpLink.Send(GameControllerCodec.monitorRequest, m.gameController)
          Behaviors.same
        }
      },
      "monitor-requests"
    )
    val self = context.self
    val statusEvents = context.spawn(Behaviors.receiveMessage[UdpLink.Event] { e =>
        self ! Gateway.MonitorStatusEvent(e)
        Behaviors.same
      }, "monitor-status-events")
    context.spawn(
      UdpLink(
        new InetSocketAddress(settings.gameControllerBindAddress, m.statusPort),
        statusEvents,
        UdpLink.Options(reuseAddress = true, maxDatagramsPerSecond = settings.gameControllerMaxDatagramsPerSecond)
      ),
      "monitor-status-link"
    )
  }

  /** A control packet from an address not trusted for game state: anyone on the field's WiFi can send one, and only the
    * configured GameController steers the gate. A readable one is still noted, so a second GameController is named.
    */
  def untrustedPacket(bytes: Array[Byte], from: InetSocketAddress): Unit = {
    untrusted += 1
    rejections.count(Rejection.UntrustedGameController, from)
    GameControllerCodec.decodeControl(bytes).foreach(heard(_, from, trusted = false, System.nanoTime()))
  }

  /** A team message heard on the team port: it counts against the budget. */
  def teamMessage(bytes: Array[Byte]): Unit = budget = budget.message(bytes.length, System.nanoTime())

  /** A robot's status message forwarded by the GameController (monitor role). */
  def forwardedStatus(bytes: Array[Byte], from: InetSocketAddress): Unit =
    // Only the GameController forwards status messages; a stranger cannot fill the view.
    if (!settings.monitor.exists(_.gameController.getAddress == from.getAddress))
      rejections.count(Rejection.UntrustedGameController, from,
        "status message from another host than the GameController")
    else
      GameControllerCodec.decodeForwardedStatus(bytes) match {
        case Right((robot, status)) => forwarded = forwarded.add(ForwardedStatus(robot, status, System.nanoTime()))
        case Left(error)            => rejections.count(Rejection.BadGameControllerPacket, from, error.describe)
      }

  /** A packet on the GameController port from a trusted address. */
  def trustedPacket(bytes: Array[Byte], from: InetSocketAddress): Unit = {
    val now = System.nanoTime()
    GameControllerCodec.decodeControl(bytes) match {
      case Right(data) if !heard(data, from, trusted = true, now) =>
        // A second trusted GameController while the first keeps sending: named in the warnings, never obeyed.
        rejections.count(Rejection.UntrustedGameController, from, "a second GameController")
      case Right(_) if trueStateFresh(now) =>
        // The monitor role: the broadcast state may lag the true one by up to 10 s; the true one rules meanwhile.
        packets += 1
      case Right(data) => control(data, from, now)
      case Left(_)
          if settings.monitor.exists(_.gameController.getAddress == from.getAddress) &&
            GameControllerCodec.decodeTrueData(bytes).isRight =>
        control(GameControllerCodec.decodeTrueData(bytes).toOption.get, from, now)
        trueStateAt = Some(now)
      case Left(error) if Datagram.isGameControllerControl(bytes) =>
        // The trusted GameController sends what this gateway cannot read (a version yet to come): it may well be
        // running a game, so the gate closes (fail safe) and says why, rather than stay open as if none were.
        rejections.count(Rejection.BadGameControllerPacket, from, error.describe)
        lastUnreadable = Some(now -> error.describe)
        gate(GameReading.Unreadable(error.describe))
      case Left(error) =>
        rejections.count(Rejection.BadGameControllerPacket, from, error.describe)
    }
  }

  /** Whether the monitor role's true state is fresh enough that the broadcast one is not used. */
  private def trueStateFresh(now: Long): Boolean =
    settings.monitor.exists(m => trueStateAt.exists(at => now - at < m.trueStateFresh.toNanos))

  /** A readable control packet that counts (broadcast, or the true state): the gate, the budget, the view. */
  private def control(data: GameControlData, from: InetSocketAddress, now: Long): Unit = {
    packets += 1
    gameFrom = Some(from)
    if (settings.teamMessages.enabled) budget = budget.game(data)
    val changed = !game.exists(_.gameState == data.gameState)
    gate(CompetitionGate.reading(data.gameState, data.version, lastUnreadable, now))
    // The 2014 GameController sends versions 8 and 7 each round; the richer (newer) packet is the one to keep.
    if (game.forall(g => rank(data.version) <= rank(g.version)) || changed) {
      game = Some(data)
      publish(GameStateUpdated(data))
    }
  }

  /** Notes the sender of a readable control packet; true when its game state counts (see GameControllerSources). */
  private def heard(data: GameControlData, from: InetSocketAddress, trusted: Boolean, now: Long): Boolean = {
    val (next, use) = sources.packet(from, data.packetNumberOnWire, trusted, now)
    if (next.others(now).nonEmpty && sources.others(now).isEmpty)
      context.log.warn("{}", next.warnings(now).mkString("; "))
    sources = next
    use
  }

  /** Where a version stands among those read: newest (richest) first. */
  private def rank(version: GameControlVersion): Int = GameControlVersion.all.indexOf(version)
}
