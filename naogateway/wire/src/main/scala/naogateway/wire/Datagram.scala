package naogateway.wire

/** A datagram received on a robot's port, sorted by its first bytes (docs/protocol.md §3 and §10). The original array
  * is kept, not copied; decoding it is the job of the codec of its kind.
  */
sealed trait Datagram extends Product with Serializable {

  /** The datagram exactly as received: the same array instance, so do not modify it. Case-class equality of datagrams
    * compares this array by reference.
    */
  def bytes: Array[Byte]
}

/** Classification of any received datagram into exactly one kind, by prefix only (docs/protocol.md §3 and §10):
  *
  *   - every datagram larger than [[WireLimits.MaxDatagramBytes]] (1400) is rejected, whatever it starts with;
  *   - `00 2A` (operation 42, big-endian) and at least 8 bytes (the shorter, 2014 header form): an FU-Remote frame;
  *   - `R G m e`: a GameController control packet; `R G r t`: a GameController return packet;
  *   - at least 2 bytes with byte 0 and byte 1 (unsigned) both below [[WireLimits.StreamSequenceLimit]] (42): a
  *     secure-stream segment (sequence number, ACK, payload);
  *   - anything else is rejected with a [[Datagram.Rejection]]: empty, too short for the kind its prefix announces,
  *     oversize, `RG` followed by an unknown type, or an unknown prefix.
  *
  * The accepted kinds cannot overlap: byte 1 of an FU-Remote frame is 42, not below 42, and byte 0 of a GameController
  * packet is `R` (82); so the order of the tests in [[classify]] does not matter. Classification is a few comparisons
  * on the first four bytes, never copies and never throws.
  */
object Datagram {

  /** Fewest bytes of an FU-Remote frame: the 8-byte header of the 2014 form (docs/protocol.md §4). */
  val FuRemoteMinBytes: Int = 8

  /** Fewest bytes that tell a GameController packet's type (`RGme`, `RGrt`). */
  val GameControllerPrefixBytes: Int = 4

  /** Fewest bytes of a secure-stream segment: sequence number and ACK (a pure ACK). */
  val StreamHeaderBytes: Int = 2

  private val R = 'R'.toInt
  private val G = 'G'.toInt

  /** A datagram starting `00 2A`: an FU-Remote frame in either header form. */
  final case class FuRemoteFrame(bytes: Array[Byte]) extends Datagram

  /** A datagram starting `RGme`: GameController control data. */
  final case class GameControllerControl(bytes: Array[Byte]) extends Datagram

  /** A datagram starting `RGrt`: a robot's return packet to the GameController. */
  final case class GameControllerReturn(bytes: Array[Byte]) extends Datagram

  /** A datagram starting with two bytes below 42: a secure-stream segment. */
  final case class StreamSegment(bytes: Array[Byte]) extends Datagram

  /** A datagram of no kind, with the reason. */
  final case class Rejected(reason: Rejection, bytes: Array[Byte]) extends Datagram

  /** Why a datagram has no kind. */
  sealed trait Rejection extends Product with Serializable {

    /** A short text for logs. */
    def describe: String
  }

  /** Every reason a datagram is rejected. */
  object Rejection {

    /** A datagram of zero bytes. */
    case object Empty extends Rejection {
      def describe: String = "empty datagram"
    }

    /** Fewer bytes than the kind its prefix announces needs (or a single byte, which announces nothing). */
    final case class TooShort(size: Int, needed: Int) extends Rejection {
      def describe: String = s"datagram of $size bytes is too short: its prefix needs at least $needed"
    }

    /** More bytes than the robot's module buffer can hold. */
    final case class Oversize(size: Int, limit: Int) extends Rejection {
      def describe: String = s"datagram of $size bytes exceeds the $limit-byte limit"
    }

    /** `RG` followed by two bytes that are neither `me` nor `rt`. */
    final case class UnknownGameControllerType(third: Int, fourth: Int) extends Rejection {
      def describe: String = f"GameController prefix RG with unknown type bytes $third%02X $fourth%02X"
    }

    /** First two bytes (unsigned) that start no known kind. */
    final case class UnknownPrefix(first: Int, second: Int) extends Rejection {
      def describe: String = f"unknown datagram prefix $first%02X $second%02X"
    }
  }

  /** Sorts a datagram into exactly one kind; keeps the array, never throws. */
  def classify(bytes: Array[Byte]): Datagram =
    if (isFuRemoteFrame(bytes)) FuRemoteFrame(bytes)
    else if (isGameControllerControl(bytes)) GameControllerControl(bytes)
    else if (isGameControllerReturn(bytes)) GameControllerReturn(bytes)
    else if (isStreamSegment(bytes)) StreamSegment(bytes)
    else Rejected(rejection(bytes), bytes)

  /** Whether `classify` gives an FU-Remote frame: `00 2A`, 8 to 1400 bytes. */
  def isFuRemoteFrame(bytes: Array[Byte]): Boolean =
    bytes.length >= FuRemoteMinBytes && withinLimit(bytes) && startsFuRemote(bytes)

  /** Whether `classify` gives GameController control data: `RGme`, at most 1400 bytes. */
  def isGameControllerControl(bytes: Array[Byte]): Boolean =
    startsGameController(bytes, 'm', 'e') && withinLimit(bytes)

  /** Whether `classify` gives a GameController return packet: `RGrt`, at most 1400 bytes. */
  def isGameControllerReturn(bytes: Array[Byte]): Boolean =
    startsGameController(bytes, 'r', 't') && withinLimit(bytes)

  /** Whether `classify` gives a secure-stream segment: bytes 0 and 1 below 42, 2 to 1400 bytes. */
  def isStreamSegment(bytes: Array[Byte]): Boolean =
    bytes.length >= StreamHeaderBytes && withinLimit(bytes) &&
      u8(bytes, 0) < WireLimits.StreamSequenceLimit && u8(bytes, 1) < WireLimits.StreamSequenceLimit

  // Called only when no kind matched, so a prefix that announces a kind here means "too short".
  private def rejection(bytes: Array[Byte]): Rejection =
    if (bytes.isEmpty) Rejection.Empty
    else if (!withinLimit(bytes)) Rejection.Oversize(bytes.length, WireLimits.MaxDatagramBytes)
    else if (bytes.length < StreamHeaderBytes) Rejection.TooShort(bytes.length, StreamHeaderBytes)
    else if (startsFuRemote(bytes)) Rejection.TooShort(bytes.length, FuRemoteMinBytes)
    else if (u8(bytes, 0) == R && u8(bytes, 1) == G) {
      if (bytes.length < GameControllerPrefixBytes) Rejection.TooShort(bytes.length, GameControllerPrefixBytes)
      else Rejection.UnknownGameControllerType(u8(bytes, 2), u8(bytes, 3))
    } else Rejection.UnknownPrefix(u8(bytes, 0), u8(bytes, 1))

  private def withinLimit(bytes: Array[Byte]): Boolean = bytes.length <= WireLimits.MaxDatagramBytes

  private def startsFuRemote(bytes: Array[Byte]): Boolean =
    bytes.length >= 2 && u8(bytes, 0) == (WireLimits.FumanoidsOperation >> 8) &&
      u8(bytes, 1) == (WireLimits.FumanoidsOperation & 0xff)

  private def startsGameController(bytes: Array[Byte], third: Char, fourth: Char): Boolean =
    bytes.length >= GameControllerPrefixBytes && u8(bytes, 0) == R && u8(bytes, 1) == G &&
      u8(bytes, 2) == third.toInt && u8(bytes, 3) == fourth.toInt

  private def u8(bytes: Array[Byte], at: Int): Int = bytes(at) & 0xff
}
