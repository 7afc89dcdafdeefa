package naogateway.gateway.gamecontroller

import java.net.InetSocketAddress

import akka.actor.typed.ActorRef
import akka.actor.typed.scaladsl.{ActorContext, Behaviors}

import naogateway.gateway.link.UdpLink
import naogateway.wire.Datagram
import naogateway.wire.gamecontroller.{
  GameControlData,
  GameControlVersion,
  GameControllerCodec,
  GameControllerError,
  SharedHeader
}
import naogateway.api.{ForwardedStatus, GameReading, GameSource, GameStateUpdated, GatewayEvent}
import naogateway.gateway.{Gateway, GatewaySettings, Rejection, RejectionLedger}

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
  private var unreadable = 0L
  private var latch = GateLatch.start(settings.competition, settings.gateOpenAfter.toNanos)
  // The last packet read by its shared header only (docs/protocol.md 10.12): when, its version and size, its state.
  private var headerOnly: Option[(Long, SharedHeader)] = None
  private var sources = GameControllerSources()
  private var trueStateAt: Option[Long] = None
  private var forwarded = ForwardedStatuses()
  private var budget = MessageBudget(settings.teamMessages)

  /** Control packets that counted (for `GatewayStats.gameControllerPackets`). */
  def packetsCounted: Long = packets

  /** The latest game state that counted, if any. */
  def state: Option[GameControlData] = game

  /** The gate's reading at the gateway's start: closed in competition mode until the trusted GameController is heard.
    */
  def start(): Unit = gate(latch.reading)

  /** The gate's present reading (the outbox holds the same). */
  def reading: GameReading = latch.reading

  /** Where game state comes from, as `GetGameSource` answers. */
  def source(now: Long): GameSource =
    GameSource(
      settings.gameControllerTrusted.describe,
      gameFrom,
      untrusted,
      Option.when(settings.teamMessages.enabled)(budget.describe(now)),
      sources.warnings(now) ++ (if (settings.teamMessages.enabled) budget.warnings(now) else Vector.empty) ++
        gateWarnings(now),
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

  /** What the gate's rule has seen that the operator should know: contradictions while it waited to open, and a
    * GameController of a version this gateway reads only by its shared header.
    */
  private def gateWarnings(now: Long): Vector[String] =
    Vector(
      Option.when(latch.contradictions > 0)(
        s"competition gate: ${latch.contradictions} contradiction(s) while it waited to open (a packet saying the " +
          "game runs, unreadable, or out of sequence between packets saying it does not: a forged packet or a second " +
          "GameController on the trusted address?)"),
      headerOnly.filter { case (at, _) => now - at < GameControllerSources.QuietNanos }.map { case (_, h) =>
        s"GameController version ${h.versionNumber} (${h.packetBytes} bytes) is not known to this gateway: only the " +
          s"header versions 18 to 20 share is read (${h.gameState}), the teams and penalties are not; update " +
          "naogateway (docs/protocol.md 10.12)"
      }
    ).flatten

  /** The trusted GameController dropped over the port's rate cap: packets not read, so the gate closes (fail safe). */
  def trustedDropped(count: Long): Unit =
    advance(latch.unreadable(s"$count packet(s) from a trusted source dropped over the rate cap"))

  /** A control packet from an address not trusted for game state: anyone on the field's WiFi can send one, and only the
    * configured GameController steers the gate. A readable one is still noted, so a second GameController is named.
    */
  def untrustedPacket(bytes: Array[Byte], from: InetSocketAddress): Unit = {
    untrusted += 1
    rejections.count(Rejection.UntrustedGameController, from)
    GameControllerCodec.decodeControl(bytes).foreach(d =>
      heard(d.packetNumberOnWire, from, trusted = false, System.nanoTime()))
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

  /** A packet on the GameController port from a trusted address. Whatever says the game runs closes the gate at once
    * (docs/protocol.md 10.7), whichever trusted sender it came from.
    */
  def trustedPacket(bytes: Array[Byte], from: InetSocketAddress): Unit = {
    val now = System.nanoTime()
    // Closes an open gate, or restarts a wait to open; a gate closed already keeps its reason.
    def closing(data: GameControlData): Unit =
      if (CompetitionGate.gameRunning(data.gameState) && (latch.open || latch.quietSince.isDefined))
        advance(latch.packet(GateLatch.known(data.gameState, data.version), data.packetNumberOnWire, now))
    GameControllerCodec.decodeControl(bytes) match {
      case Right(data) if !heard(data.packetNumberOnWire, from, trusted = true, now) =>
        // A second trusted GameController while the first keeps sending: named in the warnings, obeyed only to close.
        rejections.count(Rejection.UntrustedGameController, from, "a second GameController")
        closing(data)
      case Right(data) if trueStateFresh(now) =>
        // The monitor role: the broadcast state may lag the true one by up to 10 s; the true one rules meanwhile.
        packets += 1
        closing(data)
      case Right(data) => control(data, from, now)
      case Left(_)
          if settings.monitor.exists(_.gameController.getAddress == from.getAddress) &&
            GameControllerCodec.decodeTrueData(bytes).isRight =>
        control(GameControllerCodec.decodeTrueData(bytes).toOption.get, from, now)
        trueStateAt = Some(now)
      case Left(error) if Datagram.isGameControllerControl(bytes) =>
        GameControllerCodec.decodeSharedHeader(bytes) match {
          case Right(header) => sharedHeader(header, from, now)
          case Left(_)       =>
            // The trusted GameController sends what this gateway cannot read: it may well be running a game, so the
            // gate closes (fail safe) and says why, in words that stay the same from packet to packet.
            rejections.count(Rejection.BadGameControllerPacket, from, error.describe)
            unreadable += 1
            advance(latch.unreadable(s"${unreadableReason(error, bytes)}; $unreadable so far"))
        }
      case Left(error) =>
        rejections.count(Rejection.BadGameControllerPacket, from, error.describe)
    }
  }

  /** Why a packet is unreadable, without what changes from packet to packet (its packet number). */
  private def unreadableReason(error: GameControllerError, bytes: Array[Byte]): String = error match {
    case GameControllerError.UnknownVersion(header, found) =>
      s"$header of unknown version ${found.headOption.fold(-1)(_ & 0xff)}, ${bytes.length} bytes"
    case other => other.describe
  }

  /** A packet of an unknown version read by its shared header: the gate follows it, with a warning; the view keeps the
    * last fully read packet, since the teams cannot be read.
    */
  private def sharedHeader(h: SharedHeader, from: InetSocketAddress, now: Long): Unit =
    if (heard(Some(h.packetNumber), from, trusted = true, now)) {
      packets += 1
      gameFrom = Some(from)
      if (headerOnly.forall { case (_, last) => last.versionNumber != h.versionNumber })
        context.log.warn("GameController version {} ({} bytes) is not known: reading only its shared header",
          h.versionNumber, h.packetBytes)
      headerOnly = Some(now -> h)
      advance(latch.packet(GameReading.HeaderOnly(h.gameState, h.versionNumber, h.packetBytes), Some(h.packetNumber),
          now))
    } else if (CompetitionGate.gameRunning(h.gameState) && (latch.open || latch.quietSince.isDefined))
      advance(latch.packet(GameReading.HeaderOnly(h.gameState, h.versionNumber, h.packetBytes), Some(h.packetNumber),
          now))

  /** The gate after one more trusted packet: every packet's reading reaches the outbox. */
  private def advance(next: GateLatch): Unit = {
    latch = next
    gate(latch.reading)
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
    advance(latch.packet(GateLatch.known(data.gameState, data.version), data.packetNumberOnWire, now))
    // The 2014 GameController sends versions 8 and 7 each round; the richer (newer) packet is the one to keep.
    if (game.forall(g => rank(data.version) <= rank(g.version)) || changed) {
      game = Some(data)
      publish(GameStateUpdated(data))
    }
  }

  /** Notes the sender of a readable control packet; true when its game state counts (see GameControllerSources). */
  private def heard(packetNumber: Option[Int], from: InetSocketAddress, trusted: Boolean, now: Long): Boolean = {
    val (next, use) = sources.packet(from, packetNumber, trusted, now)
    if (next.others(now).nonEmpty && sources.others(now).isEmpty)
      context.log.warn("{}", next.warnings(now).mkString("; "))
    sources = next
    use
  }

  /** Where a version stands among those read: newest (richest) first. */
  private def rank(version: GameControlVersion): Int = GameControlVersion.all.indexOf(version)
}
