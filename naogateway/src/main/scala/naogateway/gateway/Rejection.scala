package naogateway.gateway

import naogateway.wire.{Datagram, FrameError, SignatureError}

/** Why the gateway refused a datagram: a closed set, so counters stay bounded and a warning is rate-limited per kind.
  * The values a sender chose (byte prefixes, sizes, claimed ids) never become part of a kind; they go to the debug log.
  */
sealed abstract class Rejection(val name: String) extends Product with Serializable

/** Every reason for refusing a datagram. */
object Rejection {

  /** Fewer than 2 or more than 1400 bytes, or first bytes that are neither a frame, a GameController packet nor a
    * segment.
    */
  case object Unclassifiable extends Rejection("unclassifiable")

  /** An FU-Remote frame shorter than its header or its declared payload. */
  case object TruncatedFrame extends Rejection("truncated frame")

  /** Starts `00 2A` but is no FU-Remote frame (operation or alignment byte). */
  case object NotAFrame extends Rejection("not a frame")

  /** Flags other than gzip. */
  case object BadFlags extends Rejection("bad flags")

  /** The declared payload length differs from the bytes carried. */
  case object LengthMismatch extends Rejection("length mismatch")

  /** A gzip-flagged payload that is not exactly one valid gzip member. */
  case object BadGzip extends Rejection("bad gzip")

  /** A payload that is not a valid `Message`. */
  case object BadProtobuf extends Rejection("bad protobuf")

  /** A frame or payload above the datagram limit. */
  case object Oversize extends Rejection("oversize")

  /** A GameController packet arriving on the robot port. */
  case object GameControllerOnRobotPort extends Rejection("GameController packet on the robot port")

  /** A packet on the GameController port that is no valid control packet. */
  case object BadGameControllerPacket extends Rejection("bad GameController packet")

  /** A valid control packet from an address the gateway does not trust for game state. */
  case object UntrustedGameController extends Rejection("untrusted GameController")

  /** A secure-stream segment from an address no robot is bound to. */
  case object StreamFromUnknownAddress extends Rejection("stream segment from an unknown address")

  /** A frame from an unknown address that is not a keep-alive (only keep-alives introduce robots). */
  case object UnknownSender extends Rejection("frame from an unknown sender")

  /** A robot id claimed from another robot's address, or an address claiming another robot's id. */
  case object RobotIdMismatch extends Rejection("robot id does not match the address")

  /** A robot id that belongs to a robot reached over ZeroMQ. */
  case object ZeroMqRobotId extends Rejection("robot id of a ZeroMQ robot")

  /** A new robot beyond the configured cap. */
  case object RobotCapReached extends Rejection("robot cap reached")

  /** A HaViMo2 frame whose records cannot be read. */
  case object BadHaViMo extends Rejection("bad HaViMo2 frame")

  /** A reply whose call id no caller of the gateway uses. */
  case object UnknownCallId extends Rejection("unknown call id")

  /** The robot actor had too many datagrams waiting: its backlog is full. */
  case object RobotBusy extends Rejection("robot actor busy")

  /** The gateway had too many unrouted frames waiting: its backlog is full. */
  case object GatewayBusy extends Rejection("gateway busy")

  /** A robot that must sign sent an unsigned frame. */
  case object Unsigned extends Rejection("unsigned")

  /** A field follows the signature. */
  case object SignatureNotLast extends Rejection("signature not last")

  /** The signature field is not well-formed. */
  case object MalformedSignature extends Rejection("malformed signature")

  /** The MAC does not match. */
  case object BadSignature extends Rejection("bad signature")

  /** A signed frame whose timestamp is not above the last accepted one. */
  case object Replayed extends Rejection("replayed")

  /** Every kind, in the order the link figures list them. */
  val all: Vector[Rejection] = Vector(
    Unclassifiable,
    TruncatedFrame,
    NotAFrame,
    BadFlags,
    LengthMismatch,
    BadGzip,
    BadProtobuf,
    Oversize,
    GameControllerOnRobotPort,
    BadGameControllerPacket,
    UntrustedGameController,
    StreamFromUnknownAddress,
    UnknownSender,
    RobotIdMismatch,
    ZeroMqRobotId,
    RobotCapReached,
    BadHaViMo,
    UnknownCallId,
    RobotBusy,
    GatewayBusy,
    Unsigned,
    SignatureNotLast,
    MalformedSignature,
    BadSignature,
    Replayed
  )

  /** The kind for a frame the decoder refused. */
  def of(error: FrameError): Rejection = error match {
    case _: FrameError.Truncated        => TruncatedFrame
    case _: FrameError.WrongOperation   => NotAFrame
    case _: FrameError.UnsupportedFlags => BadFlags
    case _: FrameError.LengthMismatch   => LengthMismatch
    case _: FrameError.BadGzip          => BadGzip
    case _: FrameError.BadProtobuf      => BadProtobuf
    case _: FrameError.Oversize         => Oversize
  }

  /** The kind for a datagram the classifier refused (protocol.md 3): `00 2A` too short for a header is a truncated
    * frame.
    */
  def of(rejected: Datagram.Rejection): Rejection = rejected match {
    case Datagram.Rejection.TooShort(_, needed) if needed == Datagram.FuRemoteMinBytes => TruncatedFrame
    case _: Datagram.Rejection.Oversize                                                => Oversize
    case _                                                                             => Unclassifiable
  }

  /** The kind for a signature the gateway did not accept. */
  def of(error: SignatureError): Rejection = error match {
    case SignatureError.Missing   => Unsigned
    case SignatureError.NotLast   => SignatureNotLast
    case SignatureError.Malformed => MalformedSignature
    case SignatureError.BadMac    => BadSignature
    case SignatureError.Replayed  => Replayed
  }
}
