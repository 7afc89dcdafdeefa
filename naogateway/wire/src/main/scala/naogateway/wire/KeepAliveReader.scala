package naogateway.wire

import java.nio.charset.StandardCharsets

import naogateway.proto.{Position, RobotHealth, ServoState, ServoTelemetry, Status}

/** The one-pass reading of the keep-alive's shape: `robotID`, `Status` (with its `Position`), `RobotHealth` and
  * `ServoTelemetry`.
  *
  * Every keep-alive used to be read twice: once by `WireRules.normalize` to check the rules of docs/protocol.md §5,
  * once by the decoder. This reader applies the same rules while it decodes, straight from the array. It takes only
  * input whose reading is plain: each field with the wire type its schema declares, varints that fit their 32-bit
  * fields, each sub-message at most once, no unknown fields, no groups, well-formed framing. For anything else it
  * answers `null` and the caller takes the general path (normalize, then decode), which gives the result or the error;
  * so both paths agree by construction. A malformed string needs no detour: `new String(_, UTF_8)` puts U+FFFD for each
  * bad sequence, which is the §5 reading.
  */
private[wire] object KeepAliveReader {

  // Tags (field number << 3 | wire type) this reader knows.
  private final val RobotIdTag = 8 // Message.robotID (1), varint
  private final val StatusTag = 186 // MessageContents.StatusField (23), length-delimited
  private final val RobotHealthTag = 56842 // MessageContents.RobotHealthField (7105), length-delimited
  private final val ServoTelemetryTag = 56850 // MessageContents.ServoTelemetryField (7106), length-delimited

  /** Where a reading stands: a position in the array, and where the current message ends. */
  private final class Cursor(val bytes: Array[Byte], var at: Int, var end: Int) {

    /** A varint of at most 10 bytes within `end` (a tenth byte only 01); -1 (with `at` past `end`) when it is not one.
      */
    def varint(): Long = {
      var result = 0L
      var shift = 0
      while (shift < 64) {
        if (at >= end) { at = Int.MaxValue; return -1L }
        val b = bytes(at)
        at += 1
        // A tenth byte other than 01 (the only one a negative number is written with) is overlong, and protobuf-java
        // reads its top bit one way or the other depending on where the varint lies: the general path judges it.
        if (shift == 63 && b != 1) { at = Int.MaxValue; return -1L }
        result |= (b & 0x7fL) << shift
        if (b >= 0) return result
        shift += 7
      }
      at = Int.MaxValue // longer than 10 bytes: malformed
      -1L
    }

    /** Enters a length-delimited sub-message: its length read and `end` moved to its end; the outer end to give
      * [[leave]], or -1 when the length does not fit.
      */
    def enter(): Int = {
      val n = length()
      if (n < 0) -1
      else {
        val outer = end
        end = at + n
        outer
      }
    }

    /** Leaves the sub-message [[enter]] answered `outer` for: whether it was read exactly to its end. */
    def leave(outer: Int): Boolean = {
      val complete = at == end
      end = outer
      complete
    }

    /** Whether everything read so far lay within `end`. */
    def ok: Boolean = at <= end

    /** The length of a length-delimited field, checked against what remains; -1 when it does not fit. */
    def length(): Int = {
      val n = varint()
      if (!ok || n < 0 || n > end - at) { at = Int.MaxValue; -1 }
      else n.toInt
    }

    def fixed32(): Int =
      if (end - at < 4) { at = Int.MaxValue; 0 }
      else {
        val v =
          (bytes(at) & 0xff) | (bytes(at + 1) & 0xff) << 8 | (bytes(at + 2) & 0xff) << 16 | (bytes(at + 3) & 0xff) << 24
        at += 4
        v
      }

    def fixed64(): Long = {
      val low = fixed32() & 0xffffffffL
      val high = fixed32().toLong
      low | high << 32
    }

    def string(): String = {
      val n = length()
      if (n < 0) null
      else {
        val s = new String(bytes, at, n, StandardCharsets.UTF_8)
        at += n
        s
      }
    }

    /** A tag; 0 at the end of the current message, -1 for one the general path must judge (too long, field 0). */
    def tag(): Int =
      if (at == end) 0
      else {
        val t = varint()
        if (!ok || t <= 7 || t > Int.MaxValue) -1 else t.toInt
      }
  }

  /** Whether `v`, read for an int32 (or enum) field, fits it. */
  private def fitsInt32(v: Long): Boolean = v == v.toInt.toLong

  /** Whether `v`, read for a uint32 field, fits it. */
  private def fitsUInt32(v: Long): Boolean = (v >>> 32) == 0L

  /** The contents of `length` bytes from `offset`, or null when the general path must read them. */
  def read(bytes: Array[Byte], offset: Int, length: Int): MessageContents = {
    val in = new Cursor(bytes, offset, offset + length)
    var robotId = 0
    var seenRobotId = false
    var status: Status = null
    var health: RobotHealth = null
    var servos: ServoTelemetry = null
    while (true) {
      in.tag() match {
        case 0 =>
          return if (!seenRobotId) null
          else
            MessageContents(robotId, status = Option(status), robotHealth = Option(health),
              servoTelemetry = Option(servos))
        case RobotIdTag =>
          val v = in.varint()
          if (!in.ok || !fitsInt32(v)) return null
          robotId = v.toInt
          seenRobotId = true
        case StatusTag if status eq null =>
          val outer = in.enter(); if (outer < 0) return null
          status = readStatus(in)
          if (!in.leave(outer) || (status eq null)) return null
        case RobotHealthTag if health eq null =>
          val outer = in.enter(); if (outer < 0) return null
          health = readRobotHealth(in)
          if (!in.leave(outer) || (health eq null)) return null
        case ServoTelemetryTag if servos eq null =>
          val outer = in.enter(); if (outer < 0) return null
          servos = readServoTelemetry(in)
          if (!in.leave(outer) || (servos eq null)) return null
        case _ => return null
      }
    }
    null // not reached
  }

  // Each sub-message is read between `enter` and `leave` at its own call site rather than through one helper taking the
  // reading function: that helper's one call of the function saw five of them, and once the servo keep-alive had been
  // decoded the optimising compiler no longer inlined the status's reading behind it (the codec bench's second run).

  private def readStatus(in: Cursor): Status = {
    var timestamp: Option[Long] = None
    var teamId: Option[Int] = None
    var timeOnline: Option[Int] = None
    var position: Position = null
    var belief: Option[Double] = None
    var agent: Option[String] = None
    var role: Option[String] = None
    var state: Option[String] = None
    while (true) {
      in.tag() match {
        case 0 => return Status(timestamp, teamId, timeOnline, Option(position), belief, agent, role, state)
        case 8 =>
          val v = in.varint(); if (!in.ok) return null
          timestamp = Some(v)
        case 16 =>
          val v = in.varint(); if (!in.ok || !fitsUInt32(v)) return null
          teamId = Some(v.toInt)
        case 24 =>
          val v = in.varint(); if (!in.ok || !fitsUInt32(v)) return null
          timeOnline = Some(v.toInt)
        case 58 if position eq null => // a second Position would be merged into the first: the general path does that
          val outer = in.enter(); if (outer < 0) return null
          position = readPosition(in)
          if (!in.leave(outer) || (position eq null)) return null
        case 65 =>
          val v = in.fixed64(); if (!in.ok) return null
          belief = Some(java.lang.Double.longBitsToDouble(v))
        case 98 =>
          val s = in.string(); if (s eq null) return null
          agent = Some(s)
        case 122 =>
          val s = in.string(); if (s eq null) return null
          role = Some(s)
        case 130 =>
          val s = in.string(); if (s eq null) return null
          state = Some(s)
        case _ => return null
      }
    }
    null
  }

  private def readPosition(in: Cursor): Position = {
    var x: Option[Int] = None
    var y: Option[Int] = None
    var rotation: Option[Float] = None
    while (true) {
      in.tag() match {
        case 0 => return Position(x, y, rotation)
        case 8 =>
          val v = in.varint(); if (!in.ok || !fitsInt32(v)) return null
          x = Some(v.toInt)
        case 16 =>
          val v = in.varint(); if (!in.ok || !fitsInt32(v)) return null
          y = Some(v.toInt)
        case 29 =>
          val v = in.fixed32(); if (!in.ok) return null
          rotation = Some(java.lang.Float.intBitsToFloat(v))
        case _ => return null
      }
    }
    null
  }

  private def readRobotHealth(in: Cursor): RobotHealth = {
    var voltage: Option[Float] = None
    var posture: Option[String] = None
    var uptime: Option[Int] = None
    var bootId: Option[Int] = None
    while (true) {
      in.tag() match {
        case 0 => return RobotHealth(voltage, posture, uptime, bootId)
        case 13 =>
          val v = in.fixed32(); if (!in.ok) return null
          voltage = Some(java.lang.Float.intBitsToFloat(v))
        case 18 =>
          val s = in.string(); if (s eq null) return null
          posture = Some(s)
        case 24 =>
          val v = in.varint(); if (!in.ok || !fitsUInt32(v)) return null
          uptime = Some(v.toInt)
        case 32 =>
          val v = in.varint(); if (!in.ok || !fitsUInt32(v)) return null
          bootId = Some(v.toInt)
        case _ => return null
      }
    }
    null
  }

  private def readServoTelemetry(in: Cursor): ServoTelemetry = {
    val servos = Vector.newBuilder[ServoState]
    var busErrors: Option[Int] = None
    while (true) {
      in.tag() match {
        case 0 => return ServoTelemetry(servos.result(), busErrors)
        case 10 =>
          val outer = in.enter(); if (outer < 0) return null
          val s = readServoState(in)
          if (!in.leave(outer) || (s eq null)) return null
          servos += s
        case 16 =>
          val v = in.varint(); if (!in.ok || !fitsUInt32(v)) return null
          busErrors = Some(v.toInt)
        case _ => return null
      }
    }
    null
  }

  private def readServoState(in: Cursor): ServoState = {
    var id: Option[Int] = None
    var position: Option[Int] = None
    var load: Option[Int] = None
    var voltage: Option[Int] = None
    var temperature: Option[Int] = None
    var error: Option[Int] = None
    var silent: Option[Boolean] = None
    def uint32(): Option[Int] = {
      val v = in.varint()
      if (!in.ok || !fitsUInt32(v)) None else Some(v.toInt)
    }
    while (true) {
      in.tag() match {
        // `id` is required: without it the general path gives the error.
        case 0 => return id.fold[ServoState](null)(ServoState(_, position, load, voltage, temperature, error, silent))
        case 8 =>
          id = uint32(); if (id.isEmpty) return null
        case 16 =>
          position = uint32(); if (position.isEmpty) return null
        case 24 =>
          val v = in.varint()
          val decoded = (v >>> 1) ^ -(v & 1) // zigzag (sint32)
          if (!in.ok || !fitsInt32(decoded)) return null
          load = Some(decoded.toInt)
        case 32 =>
          voltage = uint32(); if (voltage.isEmpty) return null
        case 40 =>
          temperature = uint32(); if (temperature.isEmpty) return null
        case 48 =>
          error = uint32(); if (error.isEmpty) return null
        case 56 =>
          val v = in.varint(); if (!in.ok) return null
          silent = Some(v != 0L)
        case _ => return null
      }
    }
    null
  }
}
