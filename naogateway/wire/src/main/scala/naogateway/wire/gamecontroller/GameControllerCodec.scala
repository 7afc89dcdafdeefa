package naogateway.wire.gamecontroller

import java.nio.charset.StandardCharsets

import scala.collection.immutable.ArraySeq

import naogateway.wire.gamecontroller.GameControllerError._

/** Encoder and decoder of GameController packets (docs/protocol.md §10): the `RGme` control packet in versions 20 (158
  * bytes), 19 (198 bytes), 12 (688 bytes), 8 (158 bytes) and 7 (116 bytes), the same version-20 and -19 layouts under
  * `RGTD` (the true state a monitor gets), and the `RGrt` return packet in versions 4 (32 bytes) and 2 (8 bytes). All
  * numbers are little-endian. Pure functions; decoding never throws and never guesses: a packet must have a known
  * header, a known version and exactly that version's size, or it is refused with a typed error. The one reading of a
  * version it does not know is [[decodeSharedHeader]], which the caller asks for on purpose.
  */
object GameControllerCodec {

  /** First four bytes of every control packet. */
  val ControlHeader: String = "RGme"

  /** First four bytes of the true game state the version-19 GameController sends a registered monitor. */
  val TrueDataHeader: String = "RGTD"

  /** First four bytes of every return packet. */
  val ReturnHeader: String = "RGrt"

  /** Where the version-12 and version-19 GameControllers hear the robots' return packets. */
  val ReturnPort: Int = 3939

  /** The return-packet version robots send to the 2014 and version-12 GameControllers. */
  val ReturnVersion: Int = 2

  /** Exact size of a version-2 return packet. */
  val ReturnPacketBytes: Int = 8

  /** The return-packet version robots send to the version-20 and -19 GameControllers (their status message). */
  val StatusVersion: Int = 4

  /** Exact size of a version-4 return packet. */
  val StatusPacketBytes: Int = 32

  private val HeaderBytes = 4
  private[gamecontroller] val VersionOffset = 4
  private val VersionFieldMaxBytes = GameControlVersion.all.map(_.versionBytes).max
  private[gamecontroller] val ControlHeaderBytes = ControlHeader.getBytes(StandardCharsets.US_ASCII)
  private val TrueDataHeaderBytes = TrueDataHeader.getBytes(StandardCharsets.US_ASCII)
  private val ReturnHeaderBytes = ReturnHeader.getBytes(StandardCharsets.US_ASCII)

  /** A layout of the `RGrt` return packet: its version byte and its exact size. */
  private final case class ReturnLayout(version: Int, packetBytes: Int)

  private val Return2 = ReturnLayout(ReturnVersion, ReturnPacketBytes)
  private val Return4 = ReturnLayout(StatusVersion, StatusPacketBytes)

  /** Decodes a control packet. The version decides the layout, and each version's field has its own width, all starting
    * at byte 4: byte 4 = 20, 19 or 8 is that version (a u8 field, a packet number follows); bytes 4–5 must read the u16
    * 12 for version 12; bytes 4–7 the u32 7 for version 7. Then the size must be exactly the version's.
    */
  def decodeControl(bytes: Array[Byte]): Either[GameControllerError, GameControlData] =
    for {
      _ <- checkHeader(bytes, ControlHeaderBytes, ControlHeader)
      version <- controlVersion(bytes, ControlHeader)
      _ <- checkSize(bytes, ControlHeader, version.number, version.packetBytes)
      data <- version match {
        case GameControlVersion.V20 => ModernLayouts.decodeV20(bytes)
        case GameControlVersion.V19 => ModernLayouts.decodeV19(bytes)
        case GameControlVersion.V12 => ModernLayouts.decodeV12(bytes)
        case GameControlVersion.V8  => Layouts2014.decode(Layouts2014.V8, bytes)
        case GameControlVersion.V7  => Layouts2014.decode(Layouts2014.V7, bytes)
      }
    } yield data

  /** Encodes a control packet in its version's layout, refusing fields that do not fit that layout. */
  def encodeControl(data: GameControlData): Either[GameControllerError, Array[Byte]] =
    data match {
      case d: ControlData2014 =>
        Layouts2014.of(d.version) match {
          case Some(layout) => Layouts2014.validate(layout, d).toLeft(Layouts2014.write(layout, d))
          case None         => Left(InvalidField("version", d.version.number.toLong))
        }
      case d: HlControlData    => ModernLayouts.validateV12(d).toLeft(ModernLayouts.writeV12(d))
      case d: HslControlData   => ModernLayouts.validateV19(d).toLeft(ModernLayouts.writeV19(d, ControlHeaderBytes))
      case d: Hsl20ControlData => ModernLayouts.validateV20(d).toLeft(ModernLayouts.writeV20(d, ControlHeaderBytes))
    }

  /** The versions whose shared first 18 bytes [[decodeSharedHeader]] reads: 18, and any above the newest known. */
  def sharedHeaderVersion(version: Int): Boolean =
    version == OldestSharedHeaderVersion || version > GameControlVersion.V20.number

  /** The oldest version with the shared header of versions 18 to 20. */
  val OldestSharedHeaderVersion: Int = 18

  /** The least size a packet read by its shared header may have: the header and two team entries without players (10
    * bytes each, as in versions 19 and 20).
    */
  val SharedHeaderMinPacketBytes: Int = 38

  /** The greatest size a packet read by its shared header may have (the largest known `RGme` has 688). */
  val SharedHeaderMaxPacketBytes: Int = 1024

  /** Reads the first 18 bytes of an `RGme` packet of a version this codec does not know but that plausibly keeps the
    * header versions 18, 19 and 20 share (docs/protocol.md §10.8): a u8 version of 18 or above 20, a size from
    * [[SharedHeaderMinPacketBytes]] to [[SharedHeaderMaxPacketBytes]], `stopped` and `firstHalf` 0 or 1, and a known
    * state (an unknown one cannot tell whether the game runs). Everything after the header is left unread.
    */
  def decodeSharedHeader(bytes: Array[Byte]): Either[GameControllerError, SharedHeader] =
    for {
      _ <- checkHeader(bytes, ControlHeaderBytes, ControlHeader)
      _ <- if (bytes.length <= VersionOffset) Left(TooShort(VersionOffset + 1, bytes.length)) else Right(())
      version = u8(bytes, VersionOffset)
      _ <-
        if (sharedHeaderVersion(version)) Right(())
        else Left(UnknownVersion(ControlHeader, slice(bytes, VersionOffset, VersionOffset + 1)))
      _ <-
        if (bytes.length >= SharedHeaderMinPacketBytes && bytes.length <= SharedHeaderMaxPacketBytes) Right(())
        else Left(ImplausibleSize(ControlHeader, version, SharedHeaderMinPacketBytes, SharedHeaderMaxPacketBytes,
            bytes.length))
      header <- ModernLayouts.readHeader(bytes)
      _ <- header.gameState match {
        case GameState.Unknown(code) => Left(InvalidField("state", code.toLong))
        case _                       => Right(())
      }
    } yield header

  /** Decodes the true game state a version-20 or -19 GameController sends its monitors: `RGTD` in that version's layout
    * (158 or 198 bytes).
    */
  def decodeTrueData(bytes: Array[Byte]): Either[GameControllerError, HslGameData] =
    for {
      _ <- checkHeader(bytes, TrueDataHeaderBytes, TrueDataHeader)
      version <- controlVersion(bytes, TrueDataHeader)
      _ <- checkSize(bytes, TrueDataHeader, version.number, version.packetBytes)
      data <- version match {
        case GameControlVersion.V20 => ModernLayouts.decodeV20(bytes)
        case GameControlVersion.V19 => ModernLayouts.decodeV19(bytes)
        case _ =>
          Left(UnknownVersion(TrueDataHeader, slice(bytes, VersionOffset, VersionOffset + version.versionBytes)))
      }
    } yield data

  /** Encodes the true game state as a version-20 or -19 GameController sends it to a monitor (`RGTD`). */
  def encodeTrueData(data: HslGameData): Either[GameControllerError, Array[Byte]] = data match {
    case d: HslControlData   => ModernLayouts.validateV19(d).toLeft(ModernLayouts.writeV19(d, TrueDataHeaderBytes))
    case d: Hsl20ControlData => ModernLayouts.validateV20(d).toLeft(ModernLayouts.writeV20(d, TrueDataHeaderBytes))
  }

  /** Decodes a version-2 return packet (exactly 8 bytes). */
  def decodeReturn(bytes: Array[Byte]): Either[GameControllerError, ReturnData] =
    openReturn(bytes, Return2).map { r =>
      val team = r.u8()
      val player = r.u8()
      ReturnData(team, player, ReturnMessage.fromCode(r.u8()))
    }

  /** Decodes a version-4 return packet (exactly 32 bytes). Like the GameController, it refuses a `fallen` byte other
    * than 0 or 1 and a coordinate that is not a number (NaN).
    */
  def decodeStatus(bytes: Array[Byte]): Either[GameControllerError, ReturnStatus] =
    for {
      r <- openReturn(bytes, Return4)
      player = r.u8()
      team = r.u8()
      fallen <- flag("fallen", r.u8())
      floats = Vector.fill(6)(r.f32())
      _ <- notNaN(floats)
    } yield ReturnStatus(player, team, fallen, (floats(0), floats(1), floats(2)), floats(3), (floats(4), floats(5)))

  /** Encodes a version-2 return packet, refusing numbers that do not fit a byte. */
  def encodeReturn(data: ReturnData): Either[GameControllerError, Array[Byte]] = {
    val v = ReturnVersion
    firstError(
      u8Range(v, "team", data.team.toLong),
      u8Range(v, "player", data.player.toLong),
      u8Range(v, "message", data.message.code.toLong)
    ).toLeft {
      val w = returnWriter(Return2)
      w.u8(data.team)
      w.u8(data.player)
      w.u8(data.message.code)
      w.out
    }
  }

  /** Encodes a version-4 return packet, refusing numbers that do not fit a byte and coordinates that are NaN. */
  def encodeStatus(data: ReturnStatus): Either[GameControllerError, Array[Byte]] = {
    val v = StatusVersion
    val floats = Vector(data.pose._1, data.pose._2, data.pose._3, data.ballAge, data.ball._1, data.ball._2)
    firstError(
      u8Range(v, "player", data.player.toLong),
      u8Range(v, "team", data.team.toLong),
      notNaN(floats).left.toOption
    ).toLeft {
      val w = returnWriter(Return4)
      w.u8(data.player)
      w.u8(data.team)
      w.flag(data.fallen)
      floats.foreach(w.f32)
      w.out
    }
  }

  /** First four bytes of a monitor's request for the true game state (to UDP 3636 of the version-20 and -19
    * GameControllers).
    */
  val MonitorRequestHeader: String = "RGTr"

  /** The monitor request: `RGTr` and version 0, 5 bytes. */
  def monitorRequest: Array[Byte] = MonitorRequestHeader.getBytes(StandardCharsets.US_ASCII) :+ 0.toByte

  /** Bytes of the IPv4 address before each status message the GameController forwards to a monitor (UDP 3940). */
  val ForwardPrefixBytes: Int = 4

  /** Decodes a status message forwarded to a monitor: the IPv4 address of the robot that sent it, then its `RGrt`
    * version-4 packet (36 bytes in all). The GameController forwards without checking; this decoder checks as
    * [[decodeStatus]] does.
    */
  def decodeForwardedStatus(bytes: Array[Byte]): Either[GameControllerError, (java.net.InetAddress, ReturnStatus)] =
    if (bytes.length < ForwardPrefixBytes) Left(TooShort(ForwardPrefixBytes, bytes.length))
    else
      decodeStatus(java.util.Arrays.copyOfRange(bytes, ForwardPrefixBytes, bytes.length))
        .map(java.net.InetAddress.getByAddress(java.util.Arrays.copyOfRange(bytes, 0, ForwardPrefixBytes)) -> _)

  private val FloatFields = Vector("pose[0]", "pose[1]", "pose[2]", "ballAge", "ball[0]", "ball[1]")

  private def notNaN(floats: Vector[Float]): Either[GameControllerError, Unit] =
    floats.indexWhere(_.isNaN) match {
      case -1 => Right(())
      case i  => Left(NotANumber(FloatFields(i)))
    }

  /** Checks a return packet's header, version and size against `layout`; the reader stands after the version byte. */
  private def openReturn(bytes: Array[Byte], layout: ReturnLayout): Either[GameControllerError, LeReader] =
    for {
      _ <- checkHeader(bytes, ReturnHeaderBytes, ReturnHeader)
      _ <-
        if (bytes.length <= VersionOffset) Left(TooShort(VersionOffset + 1, bytes.length))
        else if (u8(bytes, VersionOffset) != layout.version)
          Left(UnknownVersion(ReturnHeader, slice(bytes, VersionOffset, VersionOffset + 1)))
        else Right(())
      _ <- checkSize(bytes, ReturnHeader, layout.version, layout.packetBytes)
    } yield new LeReader(bytes, VersionOffset + 1)

  /** A writer of a return packet of `layout` with its header and version byte written. */
  private def returnWriter(layout: ReturnLayout): LeWriter = {
    val w = new LeWriter(layout.packetBytes)
    w.raw(ReturnHeaderBytes)
    w.u8(layout.version)
    w
  }

  private def checkHeader(bytes: Array[Byte], header: Array[Byte], name: String): Either[GameControllerError, Unit] =
    if (bytes.length < HeaderBytes) Left(TooShort(HeaderBytes, bytes.length))
    else if (java.util.Arrays.equals(bytes, 0, HeaderBytes, header, 0, HeaderBytes)) Right(())
    else Left(WrongHeader(name, slice(bytes, 0, HeaderBytes)))

  // The first byte names the candidate (every version number fits a byte); its whole field, of the width its version
  // gives, must then read that number.
  private def controlVersion(bytes: Array[Byte], header: String): Either[GameControllerError, GameControlVersion] = {
    def unknown = Left(UnknownVersion(header, slice(bytes, VersionOffset, VersionOffset + VersionFieldMaxBytes)))
    if (bytes.length <= VersionOffset) Left(TooShort(VersionOffset + 1, bytes.length))
    else
      GameControlVersion.all.find(_.number == u8(bytes, VersionOffset)) match {
        case None => unknown
        case Some(version) =>
          val end = VersionOffset + version.versionBytes
          if (bytes.length < end) Left(TooShort(end, bytes.length))
          else if (versionField(version).read(new LeReader(bytes, VersionOffset)) == version.number.toLong)
            Right(version)
          else unknown
      }
  }

  /** The width of `version`'s version field. */
  private[gamecontroller] def versionField(version: GameControlVersion): Width = Width.unsigned(version.versionBytes)

  /** Writes `version`'s number in its version field. */
  private[gamecontroller] def writeVersion(w: LeWriter, version: GameControlVersion): Unit =
    versionField(version).write(w, version.number.toLong)

  private[gamecontroller] def checkSize(
      bytes: Array[Byte],
      header: String,
      version: Int,
      size: Int
  ): Either[GameControllerError, Unit] =
    if (bytes.length == size) Right(()) else Left(WrongSize(header, version, size, bytes.length))

  private[gamecontroller] def flag(field: String, value: Int): Either[GameControllerError, Boolean] =
    value match {
      case 0     => Right(false)
      case 1     => Right(true)
      case other => Left(InvalidField(field, other.toLong))
    }

  private[gamecontroller] def firstError(checks: Option[GameControllerError]*): Option[GameControllerError] =
    checks.collectFirst { case Some(error) => error }

  private[gamecontroller] def range(
      v: Int, field: String, value: Long, min: Long, max: Long): Option[GameControllerError] =
    if (value < min || value > max) Some(OutOfRange(v, field, value, min, max)) else None

  private[gamecontroller] def fits(v: Int, field: String, value: Long, width: Width): Option[GameControllerError] =
    range(v, field, value, width.min, width.max)

  private[gamecontroller] def u8Range(v: Int, field: String, value: Long): Option[GameControllerError] =
    fits(v, field, value, Width.U8)

  private[gamecontroller] def length(field: String, expected: Int, found: Int): Option[GameControllerError] =
    if (found != expected) Some(WrongLength(field, expected, found)) else None

  // The writers run only after validate, so every Option is present and every value fits.

  private[gamecontroller] def u8(bytes: Array[Byte], at: Int): Int = bytes(at) & 0xff

  private[gamecontroller] def slice(bytes: Array[Byte], from: Int, until: Int): ArraySeq[Byte] =
    ArraySeq.unsafeWrapArray(java.util.Arrays.copyOfRange(bytes, from, math.min(until, bytes.length)))
}
