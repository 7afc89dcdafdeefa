package naogateway.gateway.robot

import java.net.InetSocketAddress

import akka.actor.typed.ActorRef

import naogateway.gateway.link.ZeroMqRobotLink
import naogateway.proto.{DebuggingCommands, DebuggingOption, RobotHealth, ServoTelemetry, Status}
import naogateway.wire.{FrameError, HaViMo, HeaderForm, MessageContents, RpcCall, RpcReply, WireLimits}
import naogateway.api.{Priority, VisionFrame}
import naogateway.gateway.Rejection

/** What goes to a robot and the bytes it becomes (the one place that builds a robot's outbound frames), and what a
  * frame from it carries. Pure: encoding reads the route and changes nothing (the option bookkeeping is `RobotState`'s,
  * done before anything is encoded).
  */
private[naogateway] object RobotFrames {

  /** One thing a frame from the robot carries, for its owner in the robot actor's family. */
  sealed trait Arrival extends Product with Serializable

  /** The kinds of arrivals. */
  object Arrival {

    /** A keep-alive, with the servo telemetry it carries (docs/protocol.md 6.8). */
    final case class KeepAlive(status: Status, health: Option[RobotHealth], servos: Option[ServoTelemetry] = None)
        extends Arrival

    /** The robot's option list (protocol.md 8). */
    final case class OptionsPushed(options: Seq[DebuggingOption]) extends Arrival

    /** A reply to a call of `owner`. */
    final case class Reply(owner: CallId.Owner, reply: RpcReply, callId: Long) extends Arrival

    /** A camera frame. */
    final case class Vision(frame: VisionFrame) extends Arrival

    /** Something the robot sent that is refused, of `kind`. */
    final case class Refused(kind: Rejection, detail: String) extends Arrival
  }

  /** Whether `contents` carries nothing but (at most) a keep-alive: nearly every frame a robot sends. */
  def keepAliveOnly(contents: MessageContents): Boolean =
    contents.debuggingCommands.isEmpty && contents.rpcResponse.isEmpty && contents.havimoRegions.isEmpty &&
      contents.havimoGrid.isEmpty

  /** What `contents` from robot `robotId` carries, in the order the robot actor hands it on. */
  def arrivals(robotId: Int, contents: MessageContents): Vector[Arrival] =
    // A frame that carries only a keep-alive (nearly every frame a robot sends) costs no collections of empty parts.
    if (keepAliveOnly(contents))
      contents.status.fold(Vector.empty[Arrival])(s =>
        Vector(Arrival.KeepAlive(s, contents.robotHealth, contents.servoTelemetry)))
    else allArrivals(robotId, contents)

  private def allArrivals(robotId: Int, contents: MessageContents): Vector[Arrival] = {
    val keepAlive = contents.status.map(Arrival.KeepAlive(_, contents.robotHealth, contents.servoTelemetry)).toVector
    val pushed = contents.debuggingCommands.flatMap(_.optionPush).map(l => Arrival.OptionsPushed(l.options)).toVector
    val replies = contents.rpcResponse.toVector.flatMap { response =>
      val reply = RpcReply.fromProto(response)
      reply.callId.toVector.map { id =>
        CallId.ownerOf(id)
          .fold[Arrival](Arrival.Refused(Rejection.UnknownCallId, s"call id $id"))(Arrival.Reply(_, reply, id))
      }
    }
    val regions = contents.havimoRegions.toVector.map { f =>
      HaViMo.decodeRegions(f.records.map(_.toByteArray).getOrElse(Array.emptyByteArray)) match {
        case Right(r) => Arrival.Vision(VisionFrame.Regions(robotId, f.frame & 0xffffffffL, f.timestamp, r))
        case Left(e)  => Arrival.Refused(Rejection.BadHaViMo, e.describe)
      }
    }
    val grid = contents.havimoGrid.toVector.map { f =>
      HaViMo.decodeGrid(f.cells.toByteArray) match {
        case Right(g) => Arrival.Vision(VisionFrame.Grid(robotId, f.frame & 0xffffffffL, f.timestamp, g))
        case Left(e)  => Arrival.Refused(Rejection.BadHaViMo, e.describe)
      }
    }
    keepAlive ++ pushed ++ replies ++ regions ++ grid
  }

  /** What can be sent to a robot. */
  sealed trait Outbound extends Product with Serializable

  /** The kinds of outbound traffic. */
  object Outbound {

    /** An RPC call (with its call id set). */
    final case class CallOut(call: RpcCall) extends Outbound

    /** Debug option management. */
    final case class DebugOut(commands: DebuggingCommands) extends Outbound

    /** A ready secure-stream segment. */
    final case class SegmentOut(bytes: Array[Byte]) extends Outbound
  }

  /** How a robot is reached: always through the outbox (the one competition gate and the team budget). */
  sealed trait Route extends Product with Serializable {
    def outbox: ActorRef[Outbox.Command]
    def to: InetSocketAddress
  }

  /** The two routes, one per transport. */
  object Route {

    /** FU-Remote frames in `form` to `to`; `signs`: the robot must sign, so the outbox signs its frames as they go. */
    final case class Datagrams(outbox: ActorRef[Outbox.Command], to: InetSocketAddress, form: HeaderForm,
        signs: Boolean = false) extends Route

    /** Serialized `Message`s, which the outbox hands to the robot's ZeroMQ `link` (`to` only names the robot). */
    final case class ZeroMq(outbox: ActorRef[Outbox.Command], to: InetSocketAddress,
        link: ActorRef[ZeroMqRobotLink.Command]) extends Route
  }

  /** The bytes of `out` for robot `robotId` on `route`, or why it cannot go. */
  def encode(robotId: Int, out: Outbound, route: Route): Either[String, Array[Byte]] = route match {
    case Route.Datagrams(_, _, form, _) =>
      val frame: Either[FrameError, Array[Byte]] = out match {
        case Outbound.CallOut(call) =>
          MessageContents.encodeFrame(MessageContents(robotId, rpcRequest = Some(call.toProto)), form)
        case Outbound.DebugOut(commands) =>
          MessageContents.encodeFrame(MessageContents(robotId, debuggingCommands = Some(commands)), form)
        case Outbound.SegmentOut(bytes) =>
          val max = WireLimits.MaxDatagramBytes
          if (bytes.length > max) Left(FrameError.Oversize(bytes.length, max)) else Right(bytes)
      }
      frame.left.map(_.describe)
    // No FU-Remote header over ZeroMQ: a ZeroMQ message carries exactly one serialized Message.
    case _: Route.ZeroMq =>
      out match {
        case Outbound.CallOut(call) => Right(MessageContents(robotId, rpcRequest = Some(call.toProto)).toProtobuf)
        case Outbound.DebugOut(c)   => Right(MessageContents(robotId, debuggingCommands = Some(c)).toProtobuf)
        case Outbound.SegmentOut(_) => Left("the secure stream does not run over ZeroMQ")
      }
  }

  /** The outbox's `Send` for `bytes` of `out`: signed when the robot must sign, but never a stream segment. */
  def send(robotId: Int, out: Outbound, bytes: Array[Byte], route: Route, priority: Priority,
      outcome: Option[ActorRef[Outbox.Outcome]], tag: Long): Outbox.Send = route match {
    case Route.Datagrams(_, to, _, signs) =>
      val signed = signs && (out match {
        case _: Outbound.SegmentOut => false
        case _                      => true
      })
      Outbox.Send(robotId, to, bytes, priority, outcome, tag, signed)
    case Route.ZeroMq(_, to, link) => Outbox.Send(robotId, to, bytes, priority, outcome, tag, via = Some(link))
  }
}
