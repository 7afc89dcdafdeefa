package robotmiddleware.cluster

import java.io.NotSerializableException
import java.net.{InetAddress, InetSocketAddress}

import com.google.protobuf.ByteString

import naogateway.api._
import naogateway.wire.{ActuatorGroup, HaViMoRegion, Posture}
import robotmiddleware.Operation
import robotmiddleware.cluster.{proto => pb}

/** The parts of the cluster's messages and their protobuf classes (`cluster.proto`), both ways: operations, failures,
  * addresses, robot snapshots and camera regions, from which `CrossNodeSerializer` builds every message it carries.
  */
private[cluster] object CrossNodeProtos {
  import CrossNodeSerializer.{Manifest => M}

  /** Bytes of kind `manifest` that do not make a message: refused, with `detail`. */
  def corrupt(manifest: String, detail: String): NotSerializableException =
    new NotSerializableException(s"CrossNodeSerializer: corrupt [$manifest]: $detail")

  /** The group named `name` in a message of kind `manifest`. A node of another build may name a group this one does not
    * have: the message is refused rather than guessed.
    */
  def group(manifest: String, name: String): ActuatorGroup =
    ActuatorGroup.parse(name).fold(e => throw corrupt(manifest, e), identity)

  def toProto(o: Operation): pb.Operation = {
    import pb.Operation.Kind
    pb.Operation(o match {
      case robotmiddleware.Operation.Walk(vx, vy, omega)  => Kind.Walk(pb.Operation.Walk(vx, vy, omega))
      case robotmiddleware.Operation.Stop()               => Kind.Stop(pb.Operation.Stop())
      case robotmiddleware.Operation.Head(pan, tilt)      => Kind.Head(pb.Operation.Head(pan, tilt))
      case robotmiddleware.Operation.Arms(ls, le, rs, re) => Kind.Arms(pb.Operation.Arms(ls, le, rs, re))
      case robotmiddleware.Operation.Posture(posture)     => Kind.Posture(pb.Operation.Posture(posture.name))
      case robotmiddleware.Operation.Say(text)            => Kind.Say(pb.Operation.Say(text))
      case robotmiddleware.Operation.RawCall(module, method, params) =>
        Kind.RawCall(pb.Operation.RawCall(module, method, params.map(_.toProto)))
    })
  }

  def fromProto(o: pb.Operation): Operation = {
    import pb.Operation.Kind
    o.kind match {
      case Kind.Walk(w) => robotmiddleware.Operation.Walk(w.vx, w.vy, w.omega)
      case Kind.Stop(_) => robotmiddleware.Operation.Stop()
      case Kind.Head(h) => robotmiddleware.Operation.Head(h.pan, h.tilt)
      case Kind.Arms(a) => robotmiddleware.Operation.Arms(a.leftShoulder, a.leftElbow, a.rightShoulder, a.rightElbow)
      case Kind.Posture(p) =>
        robotmiddleware.Operation.Posture(Posture.target(p.posture).fold(e => throw corrupt(M.Operation, e), identity))
      case Kind.Say(s) => robotmiddleware.Operation.Say(s.text)
      case Kind.RawCall(r) =>
        val params = r.params.iterator.map(naogateway.wire.RpcValue.fromProto).toVector
        robotmiddleware.Operation.RawCall(r.module, r.method, params)
      case Kind.Empty => throw corrupt(M.Operation, "no operation")
    }
  }

  def toProto(f: RobotFailure): pb.RobotFailure = {
    import pb.RobotFailure.Kind
    import naogateway.api.{RobotFailure => F}
    pb.RobotFailure(f match {
      case F.RobotOffline(robotId) => Kind.RobotOffline(pb.RobotFailure.RobotOffline(robotId))
      case F.UnknownRobot(robotId) => Kind.UnknownRobot(pb.RobotFailure.UnknownRobot(robotId))
      case F.LeaseNotHeld(robotId, group, holder) =>
        Kind.LeaseNotHeld(pb.RobotFailure.LeaseNotHeld(robotId, group.name, holder))
      case F.RuleGate(rule)                      => Kind.RuleGate(pb.RobotFailure.RuleGate(rule))
      case F.Timeout(robotId, operation, millis) => Kind.Timeout(pb.RobotFailure.Timeout(robotId, operation, millis))
      case F.RobotError(robotId, error)          => Kind.RobotError(pb.RobotFailure.RobotError(robotId, error))
      case F.SafetyHold(robotId, reason)         => Kind.SafetyHold(pb.RobotFailure.SafetyHold(robotId, reason))
      case F.Overloaded(robotId, detail)         => Kind.Overloaded(pb.RobotFailure.Overloaded(robotId, detail))
      case F.Superseded(robotId, call)           => Kind.Superseded(pb.RobotFailure.Superseded(robotId, call))
      case F.Interrupted(robotId, call)          => Kind.Interrupted(pb.RobotFailure.Interrupted(robotId, call))
    })
  }

  def fromProto(f: pb.RobotFailure): RobotFailure = {
    import pb.RobotFailure.Kind
    import naogateway.api.{RobotFailure => F}
    f.kind match {
      case Kind.RobotOffline(m) => F.RobotOffline(m.robotId)
      case Kind.UnknownRobot(m) => F.UnknownRobot(m.robotId)
      case Kind.LeaseNotHeld(m) => F.LeaseNotHeld(m.robotId, group(M.RobotFailure, m.group), m.holder)
      case Kind.RuleGate(m)     => F.RuleGate(m.rule)
      case Kind.Timeout(m)      => F.Timeout(m.robotId, m.operation, m.millis)
      case Kind.RobotError(m)   => F.RobotError(m.robotId, m.error)
      case Kind.SafetyHold(m)   => F.SafetyHold(m.robotId, m.reason)
      case Kind.Overloaded(m)   => F.Overloaded(m.robotId, m.detail)
      case Kind.Superseded(m)   => F.Superseded(m.robotId, m.call)
      case Kind.Interrupted(m)  => F.Interrupted(m.robotId, m.call)
      case Kind.Empty           => throw corrupt(M.RobotFailure, "no failure")
    }
  }

  def toProto(a: InetSocketAddress): pb.SocketAddress =
    pb.SocketAddress(Option(a.getAddress).map(ip => ByteString.copyFrom(ip.getAddress)), a.getHostString, a.getPort)

  // getByAddress with the host string never asks a name server, and InetSocketAddress equality holds.
  def fromProto(a: pb.SocketAddress): InetSocketAddress = a.ip match {
    case Some(ip) => new InetSocketAddress(InetAddress.getByAddress(a.host, ip.toByteArray), a.port)
    case None     => InetSocketAddress.createUnresolved(a.host, a.port)
  }

  def toProto(s: SigningState): pb.SigningState = s match {
    case SigningState.Off      => pb.SigningState.SIGNING_OFF
    case SigningState.Awaited  => pb.SigningState.SIGNING_AWAITED
    case SigningState.Signed   => pb.SigningState.SIGNING_SIGNED
    case SigningState.Unsigned => pb.SigningState.SIGNING_UNSIGNED
  }

  def fromProto(s: pb.SigningState): SigningState = s match {
    case pb.SigningState.SIGNING_OFF      => SigningState.Off
    case pb.SigningState.SIGNING_AWAITED  => SigningState.Awaited
    case pb.SigningState.SIGNING_SIGNED   => SigningState.Signed
    case pb.SigningState.SIGNING_UNSIGNED => SigningState.Unsigned
    case pb.SigningState.Unrecognized(v)  => throw corrupt("SigningState", s"unknown value $v")
  }

  def toProto(q: LinkQuality): pb.LinkQuality = q match {
    case LinkQuality.Good     => pb.LinkQuality.GOOD
    case LinkQuality.Degraded => pb.LinkQuality.DEGRADED
    case LinkQuality.Offline  => pb.LinkQuality.OFFLINE
  }

  def fromProto(q: pb.LinkQuality): LinkQuality = q match {
    case pb.LinkQuality.GOOD            => LinkQuality.Good
    case pb.LinkQuality.DEGRADED        => LinkQuality.Degraded
    case pb.LinkQuality.OFFLINE         => LinkQuality.Offline
    case pb.LinkQuality.Unrecognized(v) => throw corrupt("LinkQuality", s"unknown value $v")
  }

  def toProto(s: RobotSnapshot): pb.RobotSnapshot =
    pb.RobotSnapshot(
      robotId = s.robotId,
      address = toProto(s.address),
      teamId = s.teamId,
      role = s.role,
      agent = s.agent,
      posture = s.posture.map(_.name),
      batteryVoltage = s.batteryVoltage,
      uptimeMillis = s.uptimeMillis,
      bootId = s.bootId,
      position = s.position.map { case (x, y, heading) => pb.Position(x, y, heading) },
      online = s.online,
      quality = toProto(s.quality),
      receivedAtNanos = s.receivedAtNanos,
      development = Option.when(s.development)(true),
      signing = Some(toProto(s.signing)),
      servos = s.servos.map(t =>
        pb.ServoReadings(
          t.servos.map(r =>
            pb.ServoReading(r.id, r.position, r.load, r.voltage, r.temperature, Option.when(r.error != 0)(r.error),
              Option.when(r.silent)(true))),
          t.busErrors,
          t.receivedAtNanos
        ))
    )

  def fromProto(s: pb.RobotSnapshot): RobotSnapshot =
    naogateway.api.RobotSnapshot(
      robotId = s.robotId,
      address = fromProto(s.address),
      teamId = s.teamId,
      role = s.role,
      agent = s.agent,
      posture = s.posture.map(Posture.reported),
      batteryVoltage = s.batteryVoltage,
      uptimeMillis = s.uptimeMillis,
      bootId = s.bootId,
      position = s.position.map(p => (p.x, p.y, p.heading)),
      online = s.online,
      quality = fromProto(s.quality),
      receivedAtNanos = s.receivedAtNanos,
      development = s.development.contains(true),
      signing = s.signing.fold[SigningState](SigningState.Off)(fromProto),
      servos = s.servos.map(t =>
        naogateway.api.ServoReadings(
          t.servos.iterator.take(naogateway.api.ServoReadings.MaxServos).map(r =>
            naogateway.api.ServoReading(r.id, r.position, r.load, r.voltage, r.temperature, r.error.getOrElse(0),
              r.silent.contains(true))).toVector,
          t.busErrors,
          t.receivedAtNanos
        ))
    )

  def toProto(r: HaViMoRegion): pb.HaViMoRegion =
    pb.HaViMoRegion(r.index, r.colour, r.pixels, r.sumX, r.sumY, r.maxX, r.minX, r.maxY, r.minY)

  def fromProto(r: pb.HaViMoRegion): HaViMoRegion =
    HaViMoRegion(r.index, r.colour, r.pixels, r.sumX, r.sumY, r.maxX, r.minX, r.maxY, r.minY)
}
