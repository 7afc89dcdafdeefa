package naogateway.sim

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.Done
import akka.actor.typed.scaladsl.{ActorContext, Behaviors, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior}

import naogateway.gateway.link.UdpLink
import naogateway.wire.{MessageContents, RpcCall, WireLimits}

/** One simulated robot's actor while it runs: its sockets, its models and its states (see [[SimulatedRobot]]). */
private[sim] final class SimulatedRobotRun(
    settings: SimulatedRobotSettings,
    context: ActorContext[SimulatedRobot.Command],
    timers: TimerScheduler[SimulatedRobot.Command],
    receiver: ActorRef[UdpLink.Command],
    address: InetSocketAddress,
    firstSender: ActorRef[UdpLink.Command],
    firstSendingFrom: InetSocketAddress,
    fromSender: ActorRef[UdpLink.Event],
    origin: Long
) {
  import SimulatedRobot._

  // The sending socket changes on Reconnect; these belong to this actor alone.
  private var sender = firstSender
  private var sendingFrom = firstSendingFrom
  private var reconnecting = Option.empty[ActorRef[UdpLink.Command]]
  private var reconnectWaiters = Vector.empty[ActorRef[InetSocketAddress]]
  private var reconnects = 0
  private var ignoredAtSender = 0L

  /** Events of the sending socket, the same in every state: nothing that arrives there is acted on. */
  private def senderEvent(event: UdpLink.Event): Unit = event match {
    case UdpLink.Received(_, _)                                    => ignoredAtSender += 1
    case UdpLink.Bound(link, local) if reconnecting.contains(link) =>
      // The new connection is up: the old one closes, and everything from now on leaves from the new port.
      context.unwatch(sender)
      sender ! UdpLink.Unbind
      sender = link
      sendingFrom = local
      reconnecting = None
      context.watchWith(link, SocketGone(link))
      context.log.info("Simulated robot [{}] reconnected: sends from {}", id, local)
      reconnectWaiters.foreach(_ ! local)
      reconnectWaiters = Vector.empty
    case UdpLink.BindFailed(address, reason) =>
      // The old connection stays: the robot keeps sending from where it did.
      context.log.warn("Simulated robot [{}] could not reconnect on {}: {}", id, address, reason)
      reconnecting = None
      reconnectWaiters.foreach(_ ! sendingFrom)
      reconnectWaiters = Vector.empty
    case _ => ()
  }

  private def reconnect(replyTo: ActorRef[InetSocketAddress]): Unit = {
    reconnectWaiters :+= replyTo
    if (reconnecting.isEmpty) {
      reconnects += 1
      reconnecting = Some(context.spawn(
          UdpLink(new InetSocketAddress(address.getAddress, 0), fromSender,
            UdpLink.Options(receiveBufferBytes = 64 * 1024)),
          s"udp-send-$reconnects"))
    }
  }

  /** Messages every running state handles alike; `None` for the others. */
  private def always(message: Command): Option[Behavior[Command]] = message match {
    case FromSender(event) =>
      senderEvent(event)
      Some(Behaviors.same)
    case Reconnect(replyTo) =>
      reconnect(replyTo)
      Some(Behaviors.same)
    case GetReceivedCalls(replyTo) =>
      replyTo ! receivedCalls
      Some(Behaviors.same)
    case SocketGone(link) =>
      context.log.error("Simulated robot [{}] lost its socket {} and stops", id,
        if (link == receiver) address else sendingFrom)
      Some(Behaviors.stopped)
    case _ => None
  }

  private val id = settings.firmware.robotId
  private val gateway = settings.gateway

  private def now(): Long = System.nanoTime() - origin

  // The receive log: an observer's record beside the firmware, so tests can see what arrived in which order.
  private var receivedCalls = Vector.empty[ReceivedCall]

  private def logCalls(frame: Array[Byte], at: Long): Unit =
    MessageContents.decodeFrame(frame).toOption.flatMap(_._2.rpcRequest).foreach { request =>
      receivedCalls = receivedCalls.takeRight(ReceiveLogCapacity - 1) :+ ReceivedCall(at, RpcCall.fromProto(request))
    }

  def start(): Behavior[Command] = {
    val t = now()
    val booted = RobotFirmware.boot(settings.firmware, t)
    val firmware = booted.copy(nextKeepAliveAt = t + settings.keepAlivePhase.toNanos)
    val robot = Robot(firmware, freshLink(t), settings.stream.map(_(t)), RobotStats(), Long.MinValue)
    online(proceed(robot, t, None))
  }

  private def freshLink(t: Long): Option[FaithfulLink] =
    if (settings.faithfulLink) Some(FaithfulLink(settings.module, settings.cpu, settings.timeScale, settings.seed, t))
    else None

  // Powered and on the air.
  private def online(robot: Robot): Behavior[Command] =
    Behaviors.receiveMessage { message => always(message).getOrElse(onlineMessage(robot, message)) }

  private def onlineMessage(robot: Robot, message: Command): Behavior[Command] =
    message match {
      case WakeUp =>
        after(robot.copy(armedAt = Long.MinValue), None)
      case FromSocket(UdpLink.Received(bytes, from)) =>
        val counted = robot.copy(stats = robot.stats.copy(received = robot.stats.received + 1))
        after(counted, Some(bytes -> from))
      case GetState(replyTo) =>
        val t = now()
        val (next, reset) = run(robot, t, None)
        replyTo ! view(next, t, online = true, upAt = None)
        continue(next, t, reset)
      case PowerCycle(bootDelay) =>
        powerOff(robot, bootDelay, "power cycle")
      case SetBattery(volts) =>
        online(robot.copy(firmware = robot.firmware.copy(battery = math.max(0.0, volts))))
      case MoveBall(x, y) =>
        online(robot.copy(firmware = movedBall(robot.firmware, x, y)))
      case Stop(replyTo) =>
        stopping(Vector(replyTo))
      case _ =>
        Behaviors.same
    }

  private def after(robot: Robot, arrival: Option[(Array[Byte], InetSocketAddress)]): Behavior[Command] = {
    val t = now()
    val (next, reset) = run(robot, t, arrival)
    continue(next, t, reset)
  }

  private def continue(robot: Robot, t: Long, reset: Boolean): Behavior[Command] =
    if (!reset) online(arm(robot, t))
    else {
      context.log.info("Simulated robot [{}] restarts on request (boot {})", id, robot.firmware.bootId)
      flushing(robot.copy(stats = robot.stats.copy(powerCycles = robot.stats.powerCycles + 1)))
    }

  // After `system.reset`: the reply must still cross the module before the robot restarts and falls silent.
  private def flushing(robot: Robot): Behavior[Command] = {
    val t = now()
    val drained = robot.link.map(_.advance(t)).fold(robot) { step =>
      val sent = send(robot.stats, step.transmitted.map(tx => Out(tx.bytes, tx.to)))
      robot.copy(link = Some(step.link), stats = sent)
    }
    val pending = drained.link.exists(l => l.queued.nonEmpty || l.onLine.nonEmpty)
    if (!pending) goOffline(drained, settings.resetBootDelay, t)
    else {
      // Every step counts here, not only those with something to show: a packet the module loses ends the flush too.
      drained.link.flatMap(_.nextStepAt).foreach(at => timers.startSingleTimer(WakeUpKey, WakeUp, delay(at, t)))
      Behaviors.receiveMessage { message =>
        always(message).getOrElse(message match {
          case WakeUp => flushing(drained)
          case FromSocket(UdpLink.Received(_, _)) =>
            flushingCounted(drained)
          case GetState(replyTo) =>
            val at = now()
            replyTo ! view(drained, at, online = false, upAt = Some(at + settings.resetBootDelay.toNanos))
            Behaviors.same
          case PowerCycle(bootDelay) => powerOff(drained, bootDelay, "power cycle")
          case SetBattery(volts) =>
            flushing(drained.copy(firmware = drained.firmware.copy(battery = math.max(0.0, volts))))
          case MoveBall(x, y) => flushing(drained.copy(firmware = movedBall(drained.firmware, x, y)))
          case Stop(replyTo)  => stopping(Vector(replyTo))
          case _              => Behaviors.same
        })
      }
    }
  }

  private def flushingCounted(robot: Robot): Behavior[Command] =
    flushing(robot.copy(stats = robot.stats.copy(droppedWhileOff = robot.stats.droppedWhileOff + 1)))

  private def powerOff(robot: Robot, bootDelay: FiniteDuration, why: String): Behavior[Command] = {
    val t = now()
    // Battery and pose run up to the moment the power goes; whatever was due then is lost with it.
    val restarted = RobotFirmware.restart(RobotFirmware.advance(robot.firmware, t)._1, t)
    context.log.info("Simulated robot [{}] {}: silent for {} (boot {})", id, why, bootDelay, restarted.bootId)
    val stats = robot.stats.copy(powerCycles = robot.stats.powerCycles + 1)
    goOffline(robot.copy(firmware = restarted, stats = stats), bootDelay, t)
  }

  private def goOffline(robot: Robot, bootDelay: FiniteDuration, t: Long): Behavior[Command] = {
    timers.cancel(WakeUpKey)
    timers.startSingleTimer(ModuleUpKey, ModuleUp, bootDelay)
    // The module's buffer and the stream's state do not survive the power cut.
    offline(robot.copy(link = None, stream = None, armedAt = Long.MinValue), t + bootDelay.toNanos)
  }

  // Powered off, or the module is still booting: nothing goes out, nothing is answered.
  private def offline(robot: Robot, upAt: Long): Behavior[Command] =
    Behaviors.receiveMessage { message =>
      always(message).getOrElse(message match {
        case ModuleUp =>
          val t = now()
          context.log.info("Simulated robot [{}] is back (boot {})", id, robot.firmware.bootId)
          val up = robot.copy(link = freshLink(t), stream = settings.stream.map(_(t)))
          online(proceed(up, t, None))
        case FromSocket(UdpLink.Received(_, _)) =>
          offline(robot.copy(stats = robot.stats.copy(droppedWhileOff = robot.stats.droppedWhileOff + 1)), upAt)
        case GetState(replyTo) =>
          replyTo ! view(robot, now(), online = false, upAt = Some(upAt))
          Behaviors.same
        case PowerCycle(bootDelay) =>
          powerOff(robot, bootDelay, "power cycle while off")
        case SetBattery(volts) =>
          offline(robot.copy(firmware = robot.firmware.copy(battery = math.max(0.0, volts))), upAt)
        case MoveBall(x, y) =>
          offline(robot.copy(firmware = movedBall(robot.firmware, x, y)), upAt)
        case Stop(replyTo) =>
          stopping(Vector(replyTo))
        case _ =>
          Behaviors.same
      })
    }

  private def stopping(waiting: Vector[ActorRef[Done]]): Behavior[Command] = {
    timers.cancel(WakeUpKey)
    timers.cancel(ModuleUpKey)
    timers.startSingleTimer(StopKey, StopTimedOut, StopTimeout)
    // A connection still being made is not watched; it stops with this actor.
    reconnecting.foreach(_ ! UdpLink.Unbind)
    receiver ! UdpLink.Unbind
    sender ! UdpLink.Unbind
    waitForSockets(Set(receiver, sender), waiting)
  }

  private def waitForSockets(open: Set[ActorRef[UdpLink.Command]], waiting: Vector[ActorRef[Done]]): Behavior[Command] =
    Behaviors.receiveMessage {
      case SocketGone(link) if open.size > 1 => waitForSockets(open - link, waiting)
      case SocketGone(_) =>
        context.log.debug("Simulated robot [{}] closed {} and {}", id, address, sendingFrom)
        waiting.foreach(_ ! Done)
        Behaviors.stopped
      case StopTimedOut =>
        // Stopping this actor stops the links and their socket adapters, which closes the ports soon after.
        context.log.warn("Simulated robot [{}] did not see {} close within {}; stopping anyway", id, address,
          StopTimeout)
        waiting.foreach(_ ! Done)
        Behaviors.stopped
      case Stop(replyTo) => waitForSockets(open, waiting :+ replyTo)
      case Reconnect(replyTo) =>
        replyTo ! sendingFrom
        Behaviors.same
      case GetState(_) | GetReceivedCalls(_) | PowerCycle(_) | SetBattery(_) | MoveBall(_, _) | WakeUp | ModuleUp |
          FromSocket(_) | FromSender(_) =>
        Behaviors.same
    }

  // Runs the robot up to `t`, puts what is due on the socket and re-arms the wake-up timer.
  private def proceed(robot: Robot, t: Long, arrival: Option[(Array[Byte], InetSocketAddress)]): Robot =
    arm(run(robot, t, arrival)._1, t)

  private def arm(robot: Robot, t: Long): Robot = {
    // A stream endpoint that keeps asking for the present would otherwise spin the robot on zero-delay timers.
    val streamAt =
      robot.stream.fold(Long.MaxValue)(_.nextTimerAt.fold(Long.MaxValue)(math.max(_, t + MinStreamTickNanos)))
    val linkAt = robot.link.fold(Long.MaxValue)(_.nextWakeUp.getOrElse(Long.MaxValue))
    val next = math.min(robot.firmware.nextWakeUp, math.min(linkAt, streamAt))
    if (next == robot.armedAt) robot
    else {
      timers.startSingleTimer(WakeUpKey, WakeUp, delay(next, t))
      robot.copy(armedAt = next)
    }
  }

  private def delay(at: Long, t: Long): FiniteDuration = math.max(0L, at - t).nanos

  /** Everything due up to `t`, and the arrival if any; `true` when the firmware restarted on request. */
  private def run(robot0: Robot, t: Long, arrival: Option[(Array[Byte], InetSocketAddress)]): (Robot, Boolean) = {
    var robot = robot0
    val out = Vector.newBuilder[Out]

    def linkStep(step: FaithfulLink.Step): Vector[FaithfulLink.Delivery] = {
      robot = robot.copy(link = Some(step.link))
      out ++= step.transmitted.map(tx => Out(tx.bytes, tx.to))
      step.delivered
    }

    // Inbound: through the module and the CM-530's read and handling, or straight to the firmware.
    var deliveries: Vector[FaithfulLink.Delivery] = (robot.link, arrival) match {
      case (Some(link), Some((bytes, from))) => linkStep(link.arrive(bytes, from, t))
      case (Some(link), None)                => linkStep(link.advance(t))
      case (None, Some((bytes, from)))       => Vector(FaithfulLink.Delivery(bytes, Some(from), t))
      case (None, None)                      => Vector.empty
    }

    val bootId = robot.firmware.bootId
    var reset = false
    var rounds = 0
    // A reply queued now may let the CM-530 loop act again before `t`; a few rounds settle it.
    while (deliveries.nonEmpty || rounds == 0) {
      rounds += 1
      val app = Vector.newBuilder[Outgoing]
      // Stream segments the robot sends; like everything it sends, they take the radio path below.
      val segments = Vector.newBuilder[Out]
      deliveries.foreach { d =>
        if (reset) robot = robot.copy(stats = robot.stats.copy(droppedWhileOff = robot.stats.droppedWhileOff + 1))
        else {
          val at = math.max(d.at, robot.firmware.now)
          RobotDatagrams.handle(robot, d.bytes, d.from.getOrElse(gateway), at, gateway, logCalls) match {
            case (next, transmit, frames) =>
              robot = next
              segments ++= transmit
              app ++= frames
          }
          reset = robot.firmware.bootId != bootId
        }
      }
      if (!reset && rounds == 1) {
        val (advanced, due) = RobotFirmware.advance(robot.firmware, t)
        robot = robot.copy(firmware = advanced)
        app ++= due
        robot.stream.filter(_.nextTimerAt.exists(_ <= t)).foreach { s =>
          val step = s.tick(t)
          robot = robot.copy(stream = Some(step.stream))
          segments ++= step.transmit.map(Out(_, gateway))
        }
      }
      val (routed, replies) = RobotDatagrams.route(robot, app.result(), t, gateway)
      robot = routed
      val plain = segments.result() ++ replies
      deliveries = Vector.empty
      robot.link match {
        case Some(_) if plain.isEmpty => () // the link has just been caught up to `t`: nothing more is due
        case Some(link) =>
          val queued = plain.foldLeft(FaithfulLink.Step(link, Vector.empty, Vector.empty)) { (acc, o) =>
            val step = acc.link.send(o.bytes, o.to, t)
            FaithfulLink.Step(step.link, acc.transmitted ++ step.transmitted, acc.delivered ++ step.delivered)
          }
          val settled = queued.link.advance(t)
          deliveries = linkStep(FaithfulLink.Step(settled.link, queued.transmitted ++ settled.transmitted,
              queued.delivered ++ settled.delivered))
        case None =>
          out ++= plain
      }
      if (rounds >= MaxRounds && deliveries.nonEmpty) {
        // Only modelled costs that round to zero can make handling end at the instant of its read, round after round.
        context.log.warn("Simulated robot [{}] dropped {} datagram(s) handled at the same instant", id, deliveries.size)
        deliveries = Vector.empty
      }
    }
    robot = robot.copy(stats = send(robot.stats, out.result()))
    (robot, reset)
  }

  /** Puts datagrams on the socket; nothing larger than the module's 1400 bytes ever leaves a robot. */
  private def send(stats: RobotStats, out: Vector[Out]): RobotStats = {
    val (fit, oversize) = out.partition(_.bytes.length <= WireLimits.MaxDatagramBytes)
    // Always from the sending socket: the receive socket only ever receives, as the module's UDP server does.
    fit.foreach(o => sender ! UdpLink.Send(o.bytes, o.to))
    if (oversize.nonEmpty) context.log.warn("Simulated robot [{}] dropped {} oversize datagram(s)", id, oversize.size)
    stats.copy(sent = stats.sent + fit.size, oversizeDropped = stats.oversizeDropped + oversize.size)
  }

  private def movedBall(firmware: FirmwareState, x: Double, y: Double): FirmwareState =
    firmware.copy(settings = firmware.settings.copy(scene = firmware.settings.scene.copy(ballX = x, ballY = y)))

  private def view(robot: Robot, t: Long, online: Boolean, upAt: Option[Long]): RobotView = {
    val f = robot.firmware
    RobotView(
      robotId = id,
      teamId = f.settings.teamId,
      role = f.settings.role,
      address = address,
      online = online,
      onlineAgainIn = upAt.map(at => math.max(0L, at - t).nanos),
      bootId = f.bootId,
      uptimeMillis = f.settings.clock.millisAt(t - f.bootedAt),
      posture = f.posture,
      battery = f.battery,
      pose = f.pose,
      head = f.head,
      ball = (f.settings.scene.ballX, f.settings.scene.ballY),
      debugEnabled = f.debugEnabled,
      said = f.said,
      firmware = f.stats,
      stats = robot.stats.copy(ignoredAtSendingSocket = ignoredAtSender),
      module = robot.link.map(_.module.stats),
      cpu = robot.link.map(_.cpu.stats),
      sendingFrom = sendingFrom,
      clock = f.settings.clock,
      bootedAtNanos = origin + f.bootedAt
    )
  }
}
