package naogateway.sim

import java.net.InetSocketAddress

import scala.concurrent.duration._

import naogateway.proto._
import naogateway.sim.bus.{BioloidBus, BodyPostures, BusWork}
import naogateway.wire._
import naogateway.wire.gamecontroller.GameControllerCodec

/** The simulated CM-530 firmware as pure functions of state, input and time (nanoseconds). */
object RobotFirmware {

  /** Head limits, radians. */
  val PanLimit: Double = 2.0
  val TiltMin: Double = -0.6
  val TiltMax: Double = 0.5

  /** The debug options this firmware offers (name, type, description); short names keep the list under 1400 bytes. */
  val OptionCatalogue: Vector[(String, DebuggingOptionType, String)] = Vector(
    ("status.text", DebuggingOptionType.TEXT, "state changes as text"),
    ("status.table", DebuggingOptionType.TABLE, "battery, posture, uptime"),
    ("motion.plot", DebuggingOptionType.PLOTTER, "walk velocity"),
    ("world.field", DebuggingOptionType.DRAWING_FIELD, "robot and ball on the field"),
    ("world.relative", DebuggingOptionType.DRAWING_RELATIVE, "ball relative to the robot"),
    ("camera.image", DebuggingOptionType.DRAWING_CAMERA, "colour classes with regions"),
    ("havimo.regions", DebuggingOptionType.HAVIMO_REGIONS, "HaViMo2 regions"),
    ("havimo.grid", DebuggingOptionType.HAVIMO_GRID, "HaViMo2 grid")
  )

  private[sim] val CameraOptions = Set("havimo.regions", "havimo.grid", "camera.image")

  /** Whether debug option `name` is one of the camera's, which send on the camera's own clock. */
  private[sim] def isCameraOption(name: String): Boolean = CameraOptions(name)

  /** A freshly booted firmware: sitting, nothing enabled, first keep-alive due at once. */
  def boot(settings: FirmwareSettings, now: Long, bootId: Int = 1): FirmwareState =
    FirmwareState(
      settings = settings,
      bootId = bootId,
      bootedAt = now,
      now = now,
      battery = settings.initialBattery,
      posture = Posture.Sit,
      change = None,
      walk = None,
      pose = settings.startPose,
      head = (0.0, 0.0),
      arms = Vector.fill(4)(0.0),
      debugEnabled = Set.empty,
      nextKeepAliveAt = now,
      nextDebugAt = now,
      nextCameraAt = now,
      frame = 0,
      said = Vector.empty,
      game = None,
      stats = FirmwareStats(),
      // The body powers up resting where it sat down, its torque off.
      bus = BodyPostures.resting(
        BioloidBus(now, Scene.regions(settings.scene, settings.startPose, 0.0, 0.0), settings.initialBattery),
        BodyPostures.Pose.Sit),
      bodyPose = Some(BodyPostures.Pose.Sit)
    )

  /** The firmware after a restart: same settings and battery, fresh session, debug options off. */
  def restart(state: FirmwareState, now: Long): FirmwareState =
    boot(state.settings.copy(initialBattery = state.battery, startPose = state.pose), now, state.bootId + 1)

  /** Moves time forward to `now`: motion, battery, leases, keep-alives and debug output (signed, with a key). */
  def advance(state: FirmwareState, now: Long): (FirmwareState, Vector[Outgoing]) = {
    val (s, out) = advanceUnsigned(state, now)
    signed(s, out)
  }

  private def advanceUnsigned(state: FirmwareState, now: Long): (FirmwareState, Vector[Outgoing]) = {
    var s = integrate(state, now)
    val out = Vector.newBuilder[Outgoing]
    s.change.filter(_.doneAt <= now).foreach { c =>
      s = s.copy(posture = c.target, change = None, battery = s.battery - s.settings.postureChangeDrain)
      out += reply(s, c.reply, Right(Some(RpcValue.Text(c.target.name))))
    }
    s.walk.filter(_.leaseUntil <= now).foreach { _ =>
      // The lease ran out without a refresh: a lost link never leaves the robot walking.
      s = s.copy(walk = None, posture = Posture.Stand)
    }
    if (s.nextKeepAliveAt <= now) {
      // Servo telemetry rides on the first keep-alive of each telemetry period (protocol.md 6.8).
      val period = s.settings.servoTelemetryInterval
      val telemetry = period > Duration.Zero && s.nextServoTelemetryAt <= now
      val contents = keepAlive(s)
      out += Outgoing(encode(s, if (telemetry) contents.copy(servoTelemetry = Some(servoTelemetry(s))) else contents),
        Destination.Gateway)
      s = s.copy(nextKeepAliveAt = nextSlot(s.nextKeepAliveAt, s.settings.keepAliveInterval, now))
      if (telemetry)
        s = s.copy(nextServoTelemetryAt =
          if (s.nextServoTelemetryAt == Long.MinValue) now + period.toNanos
          else nextSlot(s.nextServoTelemetryAt, period, now))
    }
    if (s.debugEnabled.exists(o => !CameraOptions(o)) && s.nextDebugAt <= now) {
      FirmwareDebug.debugData(s).foreach(d =>
        out += Outgoing(encode(s, MessageContents(s.settings.robotId, debugData = Some(d))), Destination.Gateway))
      s = s.copy(nextDebugAt = nextSlot(s.nextDebugAt, s.settings.debugInterval, now))
    }
    if (s.debugEnabled.exists(CameraOptions) && s.nextCameraAt <= now) {
      val (next, frames) = FirmwareDebug.cameraFrames(s)
      frames.foreach(f => out += Outgoing(f, Destination.Gateway))
      s = next.copy(nextCameraAt = nextSlot(s.nextCameraAt, s.settings.cameraInterval, now))
    }
    s = FirmwareBody.posed(s)
    val sent = out.result()
    (s.copy(stats = s.stats.copy(datagramsOut = s.stats.datagramsOut + sent.length)), sent)
  }

  /** Handles one datagram from `from` at `now` (after advancing to `now`). With a signing key, a frame counts only when
    * the gateway signed it and its timestamp is above the last one accepted this boot; the others are counted by kind
    * and ignored. `viaStream`: the frame came as a secure-stream payload, which is not signed (docs/protocol.md 6.7).
    */
  def receive(state: FirmwareState, bytes: Array[Byte], from: InetSocketAddress, now: Long, viaStream: Boolean = false)
      : (FirmwareState, Vector[Outgoing]) = {
    val (advanced, due) = advanceUnsigned(state, now)
    val s = advanced.copy(stats = advanced.stats.copy(datagramsIn = advanced.stats.datagramsIn + 1))
    val (next, replies) = Datagram.classify(bytes) match {
      case Datagram.FuRemoteFrame(b) =>
        MessageContents.decodeFrame(b) match {
          case Right((header, contents)) =>
            authenticated(s, b, header, viaStream) match {
              case Right(accepted) => onMessage(accepted, header.form, contents, Destination.ReplyTo(from))
              case Left(refused)   => (refused, Vector.empty)
            }
          case Left(_) => (rejected(s), Vector.empty)
        }
      case Datagram.GameControllerControl(b) =>
        GameControllerCodec.decodeControl(b) match {
          case Right(data) => FirmwareGame.onGameController(s, data, from)
          case Left(_)     => (rejected(s), Vector.empty)
        }
      case _ => (rejected(s), Vector.empty)
    }
    val counted = FirmwareBody.posed(
      next.copy(stats = next.stats.copy(datagramsOut = next.stats.datagramsOut + replies.length)))
    // The reply to `system.reset` leaves before the restart: it is the old session's last frame, signed as such.
    if (counted.bootId == s.bootId) signed(counted, due ++ replies)
    else (counted, signed(s, due ++ replies)._2)
  }

  /** The state after accepting a frame from the gateway, or (`Left`) after refusing it for its signature. */
  private def authenticated(s: FirmwareState, frame: Array[Byte], header: FrameHeader, viaStream: Boolean)
      : Either[FirmwareState, FirmwareState] =
    s.settings.robotKey.filterNot(_ => viaStream) match {
      case None      => Right(s)
      case Some(key) =>
        // The robot's current boot epoch is in the MAC: the gateway's frames of an earlier boot fail here.
        FrameSigning.verifyFrame(frame, header, key, SignedLink.ToRobot(s.settings.robotId, s.bootId))
          .flatMap(body => s.gatewayWindow.accept(body.timestamp)) match {
          case Right(window) => Right(s.copy(gatewayWindow = window))
          case Left(error) =>
            val counts = s.stats.refusedSignatures
            Left(s.copy(stats = s.stats.copy(refusedSignatures = counts.updated(error.kind,
                counts.getOrElse(error.kind, 0L) + 1))))
        }
    }

  /** With a signing key, every FU-Remote frame of `out` signed in order under the robot's timestamps (boot epoch in the
    * high 32 bits, frame counter of this boot in the low); GameController answers are not frames and stay as they are.
    */
  private def signed(s: FirmwareState, out: Vector[Outgoing]): (FirmwareState, Vector[Outgoing]) =
    s.settings.robotKey match {
      case None => (s, out)
      case Some(key) =>
        var frames = s.framesSigned
        val signedOut = out.map { o =>
          if (!Datagram.isFuRemoteFrame(o.bytes)) o
          else {
            val timestamp = FrameSigning.robotTimestamp(s.bootId.toLong, frames)
            frames += 1
            // The firmware leaves room for the signature in everything it builds; no room is a bug in the simulator.
            o.copy(bytes = FrameSigning.signEncoded(o.bytes, key, SignedLink.FromRobot(s.settings.robotId), timestamp)
              .fold(e => throw new IllegalStateException(e.describe), identity))
          }
        }
        (s.copy(framesSigned = frames), signedOut)
    }

  /** Handles one decoded message: RPC calls and debug option commands; anything else is ignored. */
  def onMessage(state: FirmwareState, form: HeaderForm, contents: MessageContents, replyTo: Destination)
      : (FirmwareState, Vector[Outgoing]) = {
    val afterDebug = contents.debuggingCommands.fold((state, Vector.empty[Outgoing])) { c =>
      onDebuggingCommands(state, c, form, replyTo)
    }
    contents.rpcRequest.fold(afterDebug) { request =>
      val (s, out) = onCall(afterDebug._1, RpcCall.fromProto(request),
        PendingReply(request.callId.map(_ & 0xffffffffL), replyTo, form))
      (s, afterDebug._2 ++ out)
    }
  }

  private def onDebuggingCommands(s: FirmwareState, c: DebuggingCommands, form: HeaderForm, replyTo: Destination)
      : (FirmwareState, Vector[Outgoing]) = {
    def matching(names: Seq[String]) =
      OptionCatalogue.map(_._1).filter(o => names.exists(n => o == n || o.startsWith(n + ".")))
    val enabled = c.optionEnable.fold(s.debugEnabled)(e => s.debugEnabled ++ matching(e.options))
    val next = s.copy(debugEnabled = c.optionDisable.fold(enabled)(d => enabled -- matching(d.options)))
    val changed = c.optionEnable.isDefined || c.optionDisable.isDefined
    if (c.optionPull.contains(true) || changed) {
      val list = DebuggingCommands(optionPush = Some(DebuggingOptionList(next.debugOptions)))
      val bytes = MessageContents.encodeFrame(MessageContents(s.settings.robotId, debuggingCommands = Some(list)), form)
      (next, bytes.toOption.map(Outgoing(_, replyTo)).toVector)
    } else (next, Vector.empty)
  }

  private def floats(params: Vector[RpcValue], n: Int): Either[String, Vector[Double]] = {
    val numbers = params.collect {
      case RpcValue.Number(f) => f.toDouble
      case RpcValue.UInt(i)   => i.toDouble
    }
    if (params.length != n || numbers.length != n)
      Left(RpcReply.badParameters(s"expected $n numbers, got ${params.length} parameter(s)"))
    else if (numbers.exists(d => d.isNaN || d.isInfinite)) Left(RpcReply.badParameters("numbers must be finite"))
    else Right(numbers)
  }

  private def onCall(s0: FirmwareState, call: RpcCall, pending: PendingReply): (FirmwareState, Vector[Outgoing]) = {
    val s = s0.copy(stats = s0.stats.copy(rpcCalls = s0.stats.rpcCalls + 1))
    def answer(result: Either[String, Option[RpcValue]], next: FirmwareState = s) =
      (next, Vector(reply(next, pending, result)))
    val ok = Right(Some(RpcValue.Flag(true)))
    RpcMethod.of(call) match {
      case Some(RpcMethod.Walk) =>
        floats(call.params, 3) match {
          case Left(e) => answer(Left(e))
          case Right(Vector(vx, vy, omega)) =>
            if (s.change.isDefined) answer(Left(s"not standing: ${Posture.Moving.name}"))
            else if (s.posture != Posture.Stand && s.posture != Posture.Walking)
              answer(Left(s"not standing: ${s.posture.name}"))
            else {
              val clamp = (v: Double, limit: Double) => math.max(-limit, math.min(limit, v))
              val walk =
                Walk(clamp(vx, s.settings.maxSpeed), clamp(vy, s.settings.maxSpeed), clamp(omega, s.settings.maxTurn),
                  s.now + s.settings.walkLease.toNanos)
              val standing = walk.vx == 0 && walk.vy == 0 && walk.omega == 0
              answer(ok,
                if (standing) s.copy(walk = None, posture = Posture.Stand)
                else s.copy(walk = Some(walk), posture = Posture.Walking))
            }
          case Right(_) => answer(Left(RpcReply.badParameters("walk takes vx, vy, omega")))
        }
      case Some(RpcMethod.Stop) =>
        if (call.params.nonEmpty) answer(Left(RpcReply.badParameters("stop takes no parameters")))
        else answer(ok, s.copy(walk = None, posture = if (s.posture == Posture.Walking) Posture.Stand else s.posture))
      case Some(RpcMethod.Head) =>
        floats(call.params, 2) match {
          case Left(e) => answer(Left(e))
          case Right(Vector(pan, tilt)) =>
            if (math.abs(pan) > PanLimit || tilt < TiltMin || tilt > TiltMax)
              answer(Left(f"out of range: pan $pan%.3f (±$PanLimit), tilt $tilt%.3f ($TiltMin..$TiltMax)"))
            else answer(ok, s.copy(head = (pan, tilt)))
          case Right(_) => answer(Left(RpcReply.badParameters("head takes pan, tilt")))
        }
      case Some(RpcMethod.Arms) =>
        floats(call.params, 4).fold(e => answer(Left(e)), a => answer(ok, s.copy(arms = a)))
      case Some(RpcMethod.Posture) =>
        call.params match {
          case Vector(RpcValue.Text(name)) =>
            Posture.target(name) match {
              case Left(unknown)                        => answer(Left(RpcReply.badParameters(unknown)))
              case Right(_) if s.change.isDefined       => answer(Left(s"busy: ${Posture.Moving.name}"))
              case Right(target) if target == s.posture => answer(Right(Some(RpcValue.Text(target.name))))
              case Right(target) =>
                val duration = target match {
                  case Posture.Stand => s.settings.standUpTime
                  case Posture.Sit   => s.settings.sitDownTime
                  case _             => s.settings.crouchTime
                }
                // The reply comes when the motion ends (advance), not now.
                (s.copy(walk = None, posture = Posture.Moving,
                    change = Some(PostureChange(target, s.now + duration.toNanos, pending))),
                  Vector.empty)
            }
          case _ => answer(Left(RpcReply.badParameters("posture takes one text: sit, stand or crouch")))
        }
      case Some(RpcMethod.GetPosture) => answer(Right(Some(RpcValue.Text(s.posture.name))))
      case Some(RpcMethod.Say) =>
        call.params match {
          case Vector(RpcValue.Text(text)) => answer(ok, s.copy(said = s.said :+ text))
          case _                           => answer(Left(RpcReply.badParameters("say takes one text")))
        }
      case Some(RpcMethod.Battery) => answer(Right(Some(RpcValue.Number(s.battery.toFloat))))
      case Some(RpcMethod.Ping)    => answer(Right(Some(RpcValue.UInt(s.uptimeMillis & 0xffffffffL))))
      case Some(RpcMethod.Reset)   =>
        // Reply first, then come back as a new session (fresh uptime and sequence numbers, options off).
        val (_, out) = answer(ok)
        (restart(s, s.now), out)
      case None => answer(Left(RpcReply.unknownMethod(call.module, call.method)))
    }
  }

  private def reply(s: FirmwareState, pending: PendingReply, result: Either[String, Option[RpcValue]]): Outgoing = {
    val contents = MessageContents(s.settings.robotId, rpcResponse = Some(RpcReply(result, pending.callId).toProto))
    Outgoing(encode(contents, pending.form), pending.to)
  }

  private def rejected(s: FirmwareState): FirmwareState = s.copy(stats = s.stats.copy(rejected = s.stats.rejected + 1))

  private def nextSlot(previous: Long, interval: FiniteDuration, now: Long): Long = {
    val next = previous + interval.toNanos
    if (next > now) next else now + interval.toNanos
  }

  /** Motion and battery between `state.now` and `now`. */
  private def integrate(state: FirmwareState, now: Long): FirmwareState =
    if (now <= state.now) state
    else {
      val seconds = (now - state.now) / 1e9
      val walkingFor = state.walk.fold(0.0)(w => math.max(0L, math.min(now, w.leaseUntil) - state.now).toDouble / 1e9)
      val pose = state.walk.fold(state.pose)(w => state.pose.moved(w.vx, w.vy, w.omega, walkingFor))
      val drain = state.settings.idleDrainPerSecond * seconds + state.settings.walkDrainPerSecond * walkingFor
      val drained = math.max(0.0, state.battery - drain)
      // Sitting (not moving towards another posture) with a low battery, the robot charges up to `sitChargeUpTo`; a
      // battery above that only drains.
      val sitting = state.posture == Posture.Sit && state.change.isEmpty
      val upTo = state.settings.sitChargeUpTo
      val battery =
        if (sitting && drained < upTo) math.min(upTo, drained + state.settings.sitChargePerSecond * seconds)
        else drained
      state.copy(now = now, pose = pose, battery = battery)
    }

  private[sim] def encode(s: FirmwareState, contents: MessageContents): Array[Byte] =
    encode(contents, s.settings.headerForm)

  // The firmware only builds messages it knows fit into 1400 bytes; one that does not is a bug in the simulator.
  private def encode(contents: MessageContents, form: HeaderForm): Array[Byte] =
    MessageContents.encodeFrame(contents, form).fold(e => throw new IllegalStateException(e.describe), identity)

  /** The keep-alive: Status as FU-Remote expects it, plus this project's RobotHealth. */
  def keepAlive(s: FirmwareState): MessageContents =
    RobotReport(
      teamId = Some(s.settings.teamId),
      role = Some(s.settings.role),
      agent = Some(s.settings.agent),
      posture = Some(s.posture),
      batteryVoltage = Some(s.battery),
      uptimeMillis = Some(s.uptimeMillis),
      bootId = Some(s.bootId),
      position = Some(((s.pose.x * 1000).round.toInt, (s.pose.y * 1000).round.toInt, s.pose.theta)),
      development = s.settings.development
    ).contents(s.settings.robotId)

  /** The servo telemetry of `s` (protocol.md 6.8): the configured source's servos, or those of the robot's emulated bus
    * read at the firmware's time on the battery's voltage; at most 32, as the firmware reads.
    */
  def servoTelemetry(s: FirmwareState): ServoTelemetry =
    ServoTelemetry(
      s.settings.servoSource
        .fold[Seq[ServoState]](s.bus.advance(s.now).withVolts(s.battery).servos)(_())
        .take(32)
        .toVector,
      busErrors = Some(0))

  /** Whether the GameController packet the robot uses says the game runs (READY, SET, PLAYING): the bus bridge is
    * closed then (docs/protocol.md 6.9).
    */
  def gameRunning(s: FirmwareState): Boolean = FirmwareGame.gameRunning(s)

  /** Runs one bridged request that arrived through the secure stream on the robot's bus at `now`: the firmware after it
    * and the reply frame (signed when the robot signs), one per request (docs/protocol.md 6.9).
    */
  def busBridge(state: FirmwareState, request: BusBridge, now: Long): (FirmwareState, Array[Byte]) = {
    val s = integrate(state, now)
    val (bus, reply) = BusWork.bridge(s.bus.advance(now).withVolts(s.battery), request, gameRunning(s))
    val counted = s.copy(bus = bus, stats = s.stats.copy(busBridgeRequests = s.stats.busBridgeRequests + 1))
    val frame = BusBridgeFrame.encode(s.settings.robotId, reply, s.settings.headerForm)
      .getOrElse(throw new IllegalStateException("a bus bridge reply always fits a frame"))
    val (signedState, out) = signed(counted, Vector(Outgoing(frame, Destination.Gateway)))
    (signedState, out.head.bytes)
  }
}
