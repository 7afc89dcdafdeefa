package naogateway.sim.network

import scala.util.Random

import naogateway.api.{GatewayEvent, RobotOffline, RobotOnline, RobotRestarted, RobotSnapshot, RobotStatusUpdated}
import naogateway.wire._

/** Frames an outsider on the field's WiFi can make without the team key, as pure functions: a made-up keep-alive, one
  * signed with another key, copies of frames it recorded, and recorded frames with a bit flipped, a field added after
  * the signature, or a broken signature. Sent from a robot's own address (a forged source is easy on a shared WiFi),
  * none of them may change what the gateway believes about a robot that must sign (docs/protocol.md 6.7).
  */
object ForgedFrames {

  /** A keep-alive of robot `robotId` claiming an empty battery and a fresh session (boot `bootId`, uptime 0). */
  def keepAlive(robotId: Int, battery: Double, bootId: Int, posture: Posture = Posture.Stand): MessageContents =
    RobotReport(
      teamId = Some(1),
      role = Some("striker"),
      agent = Some("SimAgent"),
      posture = Some(posture),
      batteryVoltage = Some(battery),
      uptimeMillis = Some(0L),
      bootId = Some(bootId),
      position = Some((0, 0, 0.0))
    ).contents(robotId)

  /** `contents` as an unsigned frame. */
  def unsigned(contents: MessageContents, form: HeaderForm = HeaderForm.Legacy): Array[Byte] =
    MessageContents.encodeFrame(contents, form).fold(e => throw new IllegalArgumentException(e.describe), identity)

  /** `contents` signed as its robot's frame with that robot's key from team key `key` (not the team's) under
    * `timestamp`, which may be far above anything real.
    */
  def signedWith(
      key: SigningKey, contents: MessageContents, timestamp: Long, form: HeaderForm = HeaderForm.Legacy): Array[Byte] =
    FrameSigning.signFrame(contents, form, key.robotKey(contents.robotId), SignedLink.FromRobot(contents.robotId),
      timestamp)
      .fold(e => throw new IllegalArgumentException(e.describe), identity)

  /** A recorded frame with one bit of its protobuf bytes flipped (the header stays valid). */
  def bitFlipped(frame: Array[Byte], random: Random): Array[Byte] =
    FumanoidsFrame.decodeHeader(frame) match {
      case Right(header) if header.payloadLength > 0 =>
        val out = frame.clone()
        val at = header.form.headerBytes + random.nextInt(header.payloadLength)
        out(at) = (out(at) ^ (1 << random.nextInt(8))).toByte
        out
      case _ => frame
    }

  /** A recorded signed frame with an unknown field (50, varint 1) after its signature, which the MAC cannot cover. */
  def fieldAfterSignature(frame: Array[Byte]): Array[Byte] =
    rewrap(frame)(body => body ++ Array[Byte](0x90.toByte, 0x03, 0x01))

  /** A recorded signed frame whose signature is replaced by a `FrameSignature` of the wrong shape. */
  def malformedSignature(frame: Array[Byte]): Array[Byte] =
    rewrap(frame) { body =>
      // Tag of field 7199, length-delimited (FA C1 03), 2 bytes: field 1 as a varint, where a fixed64 belongs.
      body.dropRight(FrameSigning.FieldBytes) ++ Array[Byte](0xfa.toByte, 0xc1.toByte, 0x03, 0x02, 0x08, 0x01)
    }

  /** A batch of every kind against robot `robotId`, from the `recorded` real frames of that robot: `perKind` made-up
    * keep-alives unsigned and signed with `wrongKey`, each recorded frame replayed as it was and with a bit flipped,
    * and the recorded frames with a field after the signature or a broken signature.
    */
  def batch(robotId: Int, recorded: Vector[Array[Byte]], wrongKey: SigningKey, perKind: Int, random: Random)
      : Vector[Array[Byte]] = {
    val lie = keepAlive(robotId, battery = 10.0, bootId = 99)
    val made = (0 until perKind).flatMap { i =>
      Vector(unsigned(lie), signedWith(wrongKey, lie, (500L << 32) + i))
    }
    made.toVector ++ recorded ++ recorded.map(bitFlipped(_, random)) ++ recorded.map(fieldAfterSignature) ++
      recorded.map(malformedSignature)
  }

  /** Events of one robot that no real keep-alive of it would cause while it sits idle: a status whose session, battery
    * (beyond a few hundredths of a volt), posture, team or role differs from `truth`, a restart, or a change of
    * liveness. The robot state changes a forgery caused, as every subscriber of the gateway (the middleware and its
    * safety checks among them) would have seen them.
    */
  def stateChanges(events: Seq[GatewayEvent], truth: RobotSnapshot): Int =
    events.count {
      case RobotStatusUpdated(s) =>
        s.bootId != truth.bootId || s.posture != truth.posture || s.teamId != truth.teamId || s.role != truth.role ||
        !s.batteryVoltage.exists(v => truth.batteryVoltage.exists(t => math.abs(v - t) < 0.05))
      case _: RobotRestarted | _: RobotOffline | _: RobotOnline => true
      case _                                                    => false
    }

  private def rewrap(frame: Array[Byte])(change: Array[Byte] => Array[Byte]): Array[Byte] =
    FumanoidsFrame.decodeRaw(frame) match {
      case Right(raw) => FumanoidsFrame.encodeProtobuf(change(raw.protobuf), raw.header.form).getOrElse(frame)
      case Left(_)    => frame
    }
}
