package firmware

import java.nio.ByteBuffer
import java.nio.charset.StandardCharsets.US_ASCII
import javax.crypto.Mac
import javax.crypto.spec.SecretKeySpec

/** Signed frames version 2 ("FUSIG2", /work's agreement, docs/protocol.md 6.7) written on the test side with the JDK's
  * HMAC alone, independent of both the firmware's C and the gateway's Scala: the tests sign as a gateway does and check
  * the robot's signatures with it, so a mistake shared by one half and its own tests still shows.
  */
object Fusig2 {

  /** HMAC-SHA256 of the concatenated `parts` under `key`. */
  def hmac(key: Array[Byte], parts: Array[Byte]*): Array[Byte] = {
    val mac = Mac.getInstance("HmacSHA256")
    // An empty HMAC key is legal (RFC 2104); SecretKeySpec refuses one, so it is given as one block of zeros.
    mac.init(new SecretKeySpec(if (key.isEmpty) new Array[Byte](64) else key, "HmacSHA256"))
    parts.foreach(p => mac.update(p))
    mac.doFinal()
  }

  /** HKDF-SHA256 (RFC 5869): extract with `salt`, expand with `info` to `length` bytes. */
  def hkdf(salt: Array[Byte], ikm: Array[Byte], info: Array[Byte], length: Int): Array[Byte] = {
    val prk = hmac(salt, ikm)
    Iterator.iterate((Array.emptyByteArray, 0)) { case (t, n) => (hmac(prk, t, info, Array((n + 1).toByte)), n + 1) }
      .drop(1).map(_._1).flatten.take(length).toArray
  }

  /** The robot key of `robotId` from the team key. */
  def robotKey(teamKey: Array[Byte], robotId: Int): Array[Byte] =
    hkdf("naogateway robot key".getBytes(US_ASCII), teamKey,
      "FUSIG2".getBytes(US_ASCII) ++ ByteBuffer.allocate(4).putInt(robotId).array(), 32)

  /** Robot to gateway and gateway to robot. */
  val RobotToGateway: Byte = 1
  val GatewayToRobot: Byte = 2

  /** The 8-byte MAC over `bytes` (the Message's bytes before the signature field). */
  def mac(
      key: Array[Byte], direction: Byte, robotId: Int, epoch: Int, timestamp: Long, bytes: Array[Byte]): Array[Byte] = {
    val head = ByteBuffer.allocate(1 + 4 + 4 + 8).put(direction).putInt(robotId).putInt(epoch).putLong(timestamp)
    hmac(key, "FUSIG2".getBytes(US_ASCII), head.array(), bytes).take(8)
  }

  /** The signature field (extension 7199): key, length 19, timestamp (fixed64, little-endian) and mac. */
  def signatureField(timestamp: Long, mac: Array[Byte]): Array[Byte] =
    Array[Byte](0xfa.toByte, 0xc1.toByte, 0x03, 19, 0x09) ++
      ByteBuffer.allocate(8).order(java.nio.ByteOrder.LITTLE_ENDIAN).putLong(timestamp).array() ++
      Array[Byte](0x12, 8) ++ mac

  /** A legacy-header frame (protocol.md 4.1) around a Message's bytes. */
  def frame(message: Array[Byte]): Array[Byte] =
    Array[Byte](0, 42, 0, 0, 0, 0, 0, 0) ++ ByteBuffer.allocate(4).putInt(message.length).array() ++ message

  /** A gateway frame for `robotId` signed with `key` in the robot's `epoch` at `timestamp`. */
  def signedFrame(key: Array[Byte], robotId: Int, epoch: Int, timestamp: Long, message: Array[Byte]): Array[Byte] =
    frame(message ++ signatureField(timestamp, mac(key, GatewayToRobot, robotId, epoch, timestamp, message)))

  /** A protobuf varint. */
  def varint(v: Long): Array[Byte] =
    Iterator.iterate(v)(_ >>> 7).takeWhile(_ != 0).map(x => x & 0x7f).toArray match {
      case Array() => Array[Byte](0)
      case groups  => groups.zipWithIndex.map { case (g, i) => (if (i < groups.length - 1) g | 0x80 else g).toByte }
    }

  /** A Message for `robotId` with the Request `module.method()` and `callId`, encoded by hand (protocol.md 7.1: the
    * Request is extension 7110 of the Message; module 1, method 2, callId 15).
    */
  def request(robotId: Int, module: String, method: String, callId: Int): Array[Byte] = {
    def str(field: Int, s: String) = {
      val b = s.getBytes(US_ASCII)
      Array((field << 3 | 2).toByte) ++ varint(b.length.toLong) ++ b
    }
    val body = str(1, module) ++ str(2, method) ++ Array[Byte](0x78) ++ varint(callId.toLong)
    Array[Byte](0x08) ++ varint(robotId.toLong & 0xffffffffL) ++ varint(7110L << 3 | 2) ++ varint(
      body.length.toLong) ++ body
  }

  /** The robot's signature on a frame it sent: (epoch, counter) when the frame ends in a signature that verifies under
    * `key` for `robotId`, else None.
    */
  def verifyRobotFrame(key: Array[Byte], robotId: Int, frame: Array[Byte]): Option[(Int, Long)] = {
    // legacy (12 bytes, the length in bytes 8..11) or compact (8 bytes, the length in bytes 4..7), protocol.md 4.1
    val header = if (frame.length >= 12 && ByteBuffer.wrap(frame, 8, 4).getInt == frame.length - 12) 12 else 8
    val payload = frame.drop(header)
    if (payload.length < 23) None
    else {
      val (signed, sig) = payload.splitAt(payload.length - 23)
      val fieldKey = sig.take(5).toSeq == Seq(0xfa, 0xc1, 0x03, 19, 0x09).map(_.toByte)
      val timestamp = ByteBuffer.wrap(sig.slice(5, 13)).order(java.nio.ByteOrder.LITTLE_ENDIAN).getLong
      val epoch = (timestamp >>> 32).toInt
      val ok = fieldKey && sig(13) == 0x12 && sig(14) == 8 &&
        java.security.MessageDigest.isEqual(sig.drop(15), mac(key, RobotToGateway, robotId, epoch, timestamp, signed))
      if (ok) Some((epoch, timestamp & 0xffffffffL)) else None
    }
  }

  /** Bytes from hex digits. */
  def unhex(s: String): Array[Byte] = s.grouped(2).map(Integer.parseInt(_, 16).toByte).toArray

  /** Hex digits of bytes. */
  def hex(b: Array[Byte]): String = b.map("%02x".format(_)).mkString
}
