package naogateway.sim.gs1500m

import scala.collection.immutable.ArraySeq

/** Why the module dropped an arriving datagram. */
sealed trait LossReason extends Product with Serializable

/** The reasons for a loss. */
object LossReason {

  /** Not enough free buffer, and the module did not (or could not) overwrite older data. */
  case object BufferFull extends LossReason

  /** Larger than the whole buffer. */
  case object Oversize extends LossReason
}

/** Something that happened in the module, at simulated time `at`. */
sealed trait ModuleEvent extends Product with Serializable {

  /** When it happened (nanoseconds). */
  def at: Long
}

/** What the module reports. */
object ModuleEvent {

  /** Datagram `id` entered the buffer. */
  final case class Buffered(id: Long, at: Long, bytes: Int) extends ModuleEvent

  /** Datagram `id` was dropped on arrival. */
  final case class Lost(id: Long, at: Long, reason: LossReason) extends ModuleEvent

  /** `bytes` more of the beginning of datagram `id` were overwritten; `remaining` of it are left. */
  final case class Overwritten(id: Long, at: Long, bytes: Int, remaining: Int) extends ModuleEvent

  /** Datagram `id` was read by the CM-530; `intact` unless its beginning had been overwritten. */
  final case class ReadOut(id: Long, at: Long, intact: Boolean) extends ModuleEvent

  /** Serial bytes crossing to the CM-530 between `at` and `until`. */
  final case class ToFirmware(bytes: ArraySeq[Byte], at: Long, until: Long) extends ModuleEvent

  /** A packet from the CM-530 left the module on air. */
  final case class OnAir(cid: Int, data: ArraySeq[Byte], at: Long) extends ModuleEvent

  /** A packet from the CM-530 found no room in the buffer and was lost. */
  final case class SendLost(cid: Int, bytes: Int, at: Long) extends ModuleEvent

  /** An input the module cannot represent at all (bad connection number, unframeable sender, bad status text). */
  final case class Refused(reason: String, at: Long) extends ModuleEvent
}

/** Running totals of the module.
  *
  * @param arrived
  *   datagrams that reached the module (each is then buffered, lost or refused)
  * @param buffered
  *   datagrams that entered the buffer
  * @param lost
  *   datagrams dropped on arrival, oversize ones included
  * @param lostOversize
  *   datagrams dropped for being larger than the buffer
  * @param overwritten
  *   buffered datagrams that lost (at least) their beginning to a later arrival or send
  * @param overwrittenBytes
  *   payload bytes overwritten
  * @param readIntact
  *   datagrams the CM-530 read whole, header included
  * @param readDamaged
  *   datagrams the CM-530 read only the tail of
  * @param sends
  *   packets the CM-530 handed over, refused ones included
  * @param onAir
  *   packets that went on air
  * @param sendsLost
  *   packets that found no room
  * @param refused
  *   inputs the module cannot represent
  * @param bytesToFirmware
  *   serial bytes read by the CM-530
  * @param bytesOnAir
  *   payload bytes that went on air
  * @param peakBuffered
  *   the most buffer bytes ever in use
  */
final case class Gs1500mStats(
    arrived: Long = 0,
    buffered: Long = 0,
    lost: Long = 0,
    lostOversize: Long = 0,
    overwritten: Long = 0,
    overwrittenBytes: Long = 0,
    readIntact: Long = 0,
    readDamaged: Long = 0,
    sends: Long = 0,
    onAir: Long = 0,
    sendsLost: Long = 0,
    refused: Long = 0,
    bytesToFirmware: Long = 0,
    bytesOnAir: Long = 0,
    peakBuffered: Int = 0
)

/** The result of an input to the module: its next state and what happened. */
final case class ModuleStep(module: Gs1500mModule, events: Vector[ModuleEvent])

/** The result of a CM-530 read: the bytes it gets, when the last of them has arrived, and what happened. */
final case class ReadStep(module: Gs1500mModule, bytes: ArraySeq[Byte], doneAt: Long, events: Vector[ModuleEvent])
