package naogateway.wire

/** Dynamixel protocol 1.0 packets (docs/protocol.md 6.9): the robot's bus speaks them, the bus bridge carries them.
  * Pure byte work shared by the gateway's bridge and the simulator's emulated bus.
  *
  * Instruction packet: `FF FF id length instruction params checksum`; status packet: `FF FF id length error params
  * checksum`; length = params + 2, checksum = ~(id + length + instruction or error + params) & 0xFF.
  */
object Dynamixel {

  /** The broadcast id: every device acts, none answers. */
  val BroadcastId: Int = 0xfe

  /** Instruction codes of protocol 1.0. */
  val Ping: Int = 0x01
  val Read: Int = 0x02
  val Write: Int = 0x03
  val RegWrite: Int = 0x04
  val Action: Int = 0x05
  val Reset: Int = 0x06
  val SyncWrite: Int = 0x83

  /** Status error bits. */
  val RangeError: Int = 0x08
  val ChecksumError: Int = 0x10
  val InstructionError: Int = 0x40

  /** The shortest packet (no parameters) and the longest an 8-bit length allows. */
  val MinPacketBytes: Int = 6
  val MaxPacketBytes: Int = 4 + 255

  /** The longest instruction packet the bridge carries (docs/protocol.md 6.9). */
  val MaxRequestBytes: Int = 143

  /** One instruction packet, read and checked. */
  final case class Instruction(id: Int, instruction: Int, params: Vector[Int]) {

    /** The packet's bytes. */
    def bytes: Array[Byte] = packet(id, instruction, params)
  }

  /** One status packet, read and checked. */
  final case class Status(id: Int, error: Int, params: Vector[Int]) {

    /** The packet's bytes. */
    def bytes: Array[Byte] = packet(id, error, params)
  }

  /** The checksum over id, length, instruction (or error) and params. */
  def checksum(id: Int, length: Int, code: Int, params: Seq[Int]): Int = ~(id + length + code + params.sum) & 0xff

  /** A packet of `id`, `code` (instruction or error) and `params`, framed and checksummed. */
  def packet(id: Int, code: Int, params: Seq[Int]): Array[Byte] = {
    val length = params.length + 2
    val out = new Array[Byte](params.length + 6)
    out(0) = 0xff.toByte
    out(1) = 0xff.toByte
    out(2) = id.toByte
    out(3) = length.toByte
    out(4) = code.toByte
    // One pass, no intermediate collections: the simulated bus frames every reply here.
    var sum = id + length + code
    var at = 5
    val each = params.iterator
    while (each.hasNext) {
      val p = each.next()
      out(at) = p.toByte
      sum += p & 0xff
      at += 1
    }
    out(at) = (~sum & 0xff).toByte
    out
  }

  /** `bytes` as exactly one well-formed packet (header, length, checksum): id, code and params. */
  def parse(bytes: Array[Byte]): Option[(Int, Int, Vector[Int])] =
    if (bytes.length < MinPacketBytes || (bytes(0) & 0xff) != 0xff || (bytes(1) & 0xff) != 0xff) None
    else {
      val id = bytes(2) & 0xff
      val length = bytes(3) & 0xff
      if (length < 2 || bytes.length != length + 4 || id == 0xff) None
      else {
        val code = bytes(4) & 0xff
        val end = bytes.length - 1
        var sum = id + length + code
        var i = 5
        while (i < end) { sum += bytes(i) & 0xff; i += 1 }
        if ((~sum & 0xff) != (bytes(end) & 0xff)) None
        else {
          val params = Vector.newBuilder[Int]
          i = 5
          while (i < end) { params += bytes(i) & 0xff; i += 1 }
          Some((id, code, params.result()))
        }
      }
    }

  /** `bytes` as one well-formed instruction packet. */
  def instruction(bytes: Array[Byte]): Option[Instruction] = parse(bytes).map { case (i, c, p) => Instruction(i, c, p) }

  /** `bytes` as one well-formed status packet. */
  def status(bytes: Array[Byte]): Option[Status] = parse(bytes).map { case (i, e, p) => Status(i, e, p) }

  /** Splits a byte stream into packets (docs/protocol.md 6.9, at the gateway): bytes before `FF FF` are skipped, a
    * packet whose length or checksum is wrong is dropped and counted, and at most `capacity` bytes wait for the rest of
    * a packet (a packet longer than that is dropped). Immutable; feed it with [[Reassembly.feed]].
    *
    * @param pending
    *   bytes received that are not yet a whole packet (they start with `FF FF`, or are a lone `FF`)
    * @param skipped
    *   bytes skipped while looking for `FF FF`
    * @param dropped
    *   packets dropped for their length or checksum
    */
  final case class Reassembly(
      pending: Vector[Byte] = Vector.empty,
      skipped: Long = 0,
      dropped: Long = 0,
      capacity: Int = MaxPacketBytes,
      maxPacketBytes: Int = MaxPacketBytes
  ) {

    /** The reassembly after `bytes`, with the whole packets found in them, in order. */
    def feed(bytes: Array[Byte]): (Reassembly, Vector[Array[Byte]]) = {
      var buffer = pending ++ bytes
      var skip = skipped
      var drop = dropped
      val out = Vector.newBuilder[Array[Byte]]
      var more = true
      while (more) {
        // Skip to FF FF (a lone FF at the end may be the first half).
        val start = buffer.indexWhere(_ == 0xff.toByte)
        if (start < 0) {
          skip += buffer.length; buffer = Vector.empty; more = false
        } else {
          if (start > 0) { skip += start; buffer = buffer.drop(start) }
          if (buffer.length < 2) more = false
          else if (buffer(1) != 0xff.toByte) { skip += 1; buffer = buffer.drop(1) }
          else if (buffer.length >= 3 && buffer(2) == 0xff.toByte) {
            // FF FF FF: the first FF is noise before the header.
            skip += 1; buffer = buffer.drop(1)
          } else if (buffer.length < 4) more = false
          else {
            val total = (buffer(3) & 0xff) + 4
            if ((buffer(3) & 0xff) < 2 || total > maxPacketBytes) {
              drop += 1; buffer = buffer.drop(2)
            } else if (buffer.length < total) more = false
            else {
              val candidate = buffer.take(total).toArray
              if (parse(candidate).isDefined) { out += candidate; buffer = buffer.drop(total) }
              else { drop += 1; buffer = buffer.drop(2) }
            }
          }
        }
      }
      if (buffer.length > capacity) { drop += 1; buffer = Vector.empty }
      (copy(pending = buffer, skipped = skip, dropped = drop), out.result())
    }
  }

  /** How many status bytes a request is due to bring back (docs/protocol.md 6.9): none for broadcast and sync write, 6
    * + n for a read of n bytes, 6 otherwise. The device's status-return level may still make it answer nothing.
    */
  def statusBytesDue(request: Instruction): Int =
    if (request.id == BroadcastId || request.instruction == SyncWrite) 0
    else if (request.instruction == Read && request.params.length == 2) 6 + request.params(1)
    else 6
}
