package naogateway.wire

import com.google.protobuf.ByteString

import naogateway.proto.{MixedValue, Request, Response}

/** A parameter or return value of a robot call, the domain side of `MixedValue`. */
sealed trait RpcValue extends Product with Serializable {

  /** The wire form. */
  def toProto: MixedValue
}

/** The kinds of `RpcValue`, one per field of `MixedValue`. */
object RpcValue {

  /** A text. */
  final case class Text(value: String) extends RpcValue { def toProto: MixedValue = MixedValue(string = Some(value)) }

  /** An unsigned 32-bit number (negative numbers travel as `Number`). */
  final case class UInt(value: Long) extends RpcValue {
    require(value >= 0 && value <= 0xffffffffL, s"$value does not fit an unsigned 32-bit int")
    def toProto: MixedValue = MixedValue(int = Some(value.toInt))
  }

  /** A 32-bit float. */
  final case class Number(value: Float) extends RpcValue { def toProto: MixedValue = MixedValue(float = Some(value)) }

  /** Raw bytes. */
  final case class Binary(value: Vector[Byte]) extends RpcValue {
    def toProto: MixedValue = MixedValue(binary = Some(ByteString.copyFrom(value.toArray)))
  }

  /** A truth value. */
  final case class Flag(value: Boolean) extends RpcValue { def toProto: MixedValue = MixedValue(bool = Some(value)) }

  /** A list of values (also the empty value). */
  final case class Items(values: Vector[RpcValue]) extends RpcValue {
    def toProto: MixedValue = MixedValue(array = values.map(_.toProto))
  }

  /** Reads the wire form: the first set field wins, an empty value is an empty list. */
  def fromProto(m: MixedValue): RpcValue =
    m.string.map(Text(_): RpcValue)
      .orElse(m.int.map(i => UInt(i & 0xffffffffL)))
      .orElse(m.float.map(Number(_)))
      .orElse(m.binary.map(b => Binary(b.toByteArray.toVector)))
      .orElse(m.bool.map(Flag(_)))
      .getOrElse(Items(m.array.iterator.map(fromProto).toVector))
}

/** A call to a robot: `module.method(params)`, with the correlation id that pairs it with its reply. */
final case class RpcCall(module: String, method: String, params: Vector[RpcValue], callId: Option[Long] = None) {

  /** `module.method`, as it appears in logs and errors. */
  def name: String = s"$module.$method"

  /** The wire form. */
  def toProto: Request = Request(module, method, params.map(_.toProto), callId.map(_.toInt))
}

/** Reading calls from the wire. */
object RpcCall {

  /** The domain form of a wire request. */
  def fromProto(r: Request): RpcCall =
    RpcCall(r.module, r.method, r.params.iterator.map(RpcValue.fromProto).toVector, r.callId.map(_ & 0xffffffffL))
}

/** A robot's answer to a call: a value or an error text, with the call's correlation id. */
final case class RpcReply(result: Either[String, Option[RpcValue]], callId: Option[Long] = None) {

  /** The wire form. */
  def toProto: Response = Response(
    returnval = result.toOption.flatten.map(_.toProto),
    error = result.left.toOption,
    callId = callId.map(_.toInt)
  )
}

/** Reading replies from the wire, and the error texts robots use. */
object RpcReply {

  /** The domain form of a wire response; an error text wins over a value. */
  def fromProto(r: Response): RpcReply =
    RpcReply(r.error.toLeft(r.returnval.map(RpcValue.fromProto)), r.callId.map(_ & 0xffffffffL))

  /** The error text for a module or method the robot does not have (the heartbeat's probe relies on it). */
  def unknownMethod(module: String, method: String): String = s"unknown method: $module.$method"

  /** The error text for parameters of the wrong number or kind. */
  def badParameters(detail: String): String = s"bad parameters: $detail"
}
