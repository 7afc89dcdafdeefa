package naogateway.wire.gamecontroller

import java.nio.charset.StandardCharsets

import scala.collection.immutable.ArraySeq

import naogateway.wire.gamecontroller.GameControllerError._

/**
 * Encoder and decoder of GameController packets (docs/protocol.md §3 and §10): the `RGme` control packet in versions 8
 * (158 bytes) and 7 (116 bytes), and the `RGrt` return packet in version 2 (8 bytes). All numbers are
 * little-endian. Pure functions; decoding never throws and never guesses: a packet must have a known
 * version and exactly that version's size, or it is refused with a typed error.
 */
object GameControllerCodec {

  /** First four bytes of every control packet. */
  val ControlHeader: String = "RGme"

  /** First four bytes of every return packet. */
  val ReturnHeader: String = "RGrt"

  /** The return-packet version robots send to this GameController (the vectors README: version 2). */
  val ReturnVersion: Int = 2

  /** Exact size of a version-2 return packet. */
  val ReturnPacketBytes: Int = 8

  private val HeaderBytes = 4
  private val VersionOffset = 4
  private val V7VersionBytes = 4
  private val ControlHeaderBytes = ControlHeader.getBytes(StandardCharsets.US_ASCII)
  private val ReturnHeaderBytes = ReturnHeader.getBytes(StandardCharsets.US_ASCII)

  private val U8Max = 0xffL
  private val U16Max = 0xffffL
  private val U32Max = 0xffffffffL
  private val I16Min = Short.MinValue.toLong
  private val I16Max = Short.MaxValue.toLong

  /**
   * Decodes a control packet. The version decides the layout: byte 4 = 8 is version 8 (a u8 field);
   * otherwise bytes 4–7 must read the u32 7 (version 7). Both start with their number in byte 4, and a
   * version-8 packet has its packet number in byte 5, so only version 7 is read as four bytes.
   */
  def decodeControl(bytes: Array[Byte]): Either[GameControllerError, GameControlData] =
    for {
      _ <- checkHeader(bytes, ControlHeaderBytes, ControlHeader)
      version <- controlVersion(bytes)
      _ <- checkSize(bytes, ControlHeader, version.number, version.packetBytes)
      data <- version match {
        case GameControlVersion.V8 => decodeV8(bytes)
        case GameControlVersion.V7 => decodeV7(bytes)
      }
    } yield data

  /** Encodes a control packet in `data.version`'s layout, refusing fields that do not fit that layout. */
  def encodeControl(data: GameControlData): Either[GameControllerError, Array[Byte]] =
    validate(data).toLeft(data.version match {
      case GameControlVersion.V8 => writeV8(data)
      case GameControlVersion.V7 => writeV7(data)
    })

  /** Decodes a version-2 return packet (exactly 8 bytes). */
  def decodeReturn(bytes: Array[Byte]): Either[GameControllerError, ReturnData] =
    for {
      _ <- checkHeader(bytes, ReturnHeaderBytes, ReturnHeader)
      _ <-
        if (bytes.length <= VersionOffset) Left(TooShort(VersionOffset + 1, bytes.length))
        else if (u8(bytes, VersionOffset) != ReturnVersion)
          Left(UnknownVersion(ReturnHeader, slice(bytes, VersionOffset, VersionOffset + 1)))
        else Right(())
      _ <- checkSize(bytes, ReturnHeader, ReturnVersion, ReturnPacketBytes)
    } yield ReturnData(u8(bytes, 5), u8(bytes, 6), ReturnMessage.fromCode(u8(bytes, 7)))

  /** Encodes a version-2 return packet, refusing numbers that do not fit a byte. */
  def encodeReturn(data: ReturnData): Either[GameControllerError, Array[Byte]] = {
    val v = ReturnVersion
    firstError(
      u8Range(v, "team", data.team.toLong),
      u8Range(v, "player", data.player.toLong),
      u8Range(v, "message", data.message.code.toLong)
    ).toLeft {
      val w = new Writer(ReturnPacketBytes)
      w.raw(ReturnHeaderBytes)
      w.u8(ReturnVersion)
      w.u8(data.team)
      w.u8(data.player)
      w.u8(data.message.code)
      w.out
    }
  }

  private def checkHeader(bytes: Array[Byte], header: Array[Byte], name: String): Either[GameControllerError, Unit] =
    if (bytes.length < HeaderBytes) Left(TooShort(HeaderBytes, bytes.length))
    else if (java.util.Arrays.equals(bytes, 0, HeaderBytes, header, 0, HeaderBytes)) Right(())
    else Left(WrongHeader(name, slice(bytes, 0, HeaderBytes)))

  private def controlVersion(bytes: Array[Byte]): Either[GameControllerError, GameControlVersion] =
    if (bytes.length <= VersionOffset) Left(TooShort(VersionOffset + 1, bytes.length))
    else if (u8(bytes, VersionOffset) == GameControlVersion.V8.number) Right(GameControlVersion.V8)
    else if (u8(bytes, VersionOffset) != GameControlVersion.V7.number)
      Left(UnknownVersion(ControlHeader, slice(bytes, VersionOffset, VersionOffset + V7VersionBytes)))
    else if (bytes.length < VersionOffset + V7VersionBytes) Left(TooShort(VersionOffset + V7VersionBytes, bytes.length))
    else if (new Reader(bytes, VersionOffset).u32() == GameControlVersion.V7.number.toLong) Right(GameControlVersion.V7)
    else Left(UnknownVersion(ControlHeader, slice(bytes, VersionOffset, VersionOffset + V7VersionBytes)))

  private def checkSize(
      bytes: Array[Byte],
      header: String,
      version: Int,
      size: Int
  ): Either[GameControllerError, Unit] =
    if (bytes.length == size) Right(()) else Left(WrongSize(header, version, size, bytes.length))

  private def decodeV8(bytes: Array[Byte]): Either[GameControllerError, GameControlData] = {
    val r = new Reader(bytes, VersionOffset + 1)
    val packetNumber = r.u8()
    val playersPerTeam = r.u8()
    val gameState = GameState.fromCode(r.u8())
    val firstHalf = r.u8()
    val kickOffTeam = KickOffTeam.fromCode(r.u8())
    val secondaryGameState = SecondaryGameState.fromCode(r.u8())
    val dropInTeam = TeamColour.fromCode(r.u8())
    val dropInTime = r.i16()
    val secsRemaining = r.i16()
    val secondaryTime = r.i16()
    val team0 = teamV8(r)
    val team1 = teamV8(r)
    flag("firstHalf", firstHalf).map { half =>
      GameControlData(
        version = GameControlVersion.V8,
        packetNumber = Some(packetNumber),
        playersPerTeam = playersPerTeam,
        gameState = gameState,
        firstHalf = half,
        kickOffTeam = kickOffTeam,
        secondaryGameState = secondaryGameState,
        dropInTeam = dropInTeam,
        dropInTime = dropInTime,
        secsRemaining = secsRemaining.toLong,
        secondaryTime = Some(secondaryTime),
        team0 = team0,
        team1 = team1
      )
    }
  }

  private def teamV8(r: Reader): TeamInfo = {
    val teamNumber = r.u8()
    val teamColour = TeamColour.fromCode(r.u8())
    val score = r.u8()
    val penaltyShot = r.u8()
    val singleShots = r.u16()
    val coachMessage = r.take(TeamInfo.CoachMessageBytes)
    val coach = playerV8(r)
    val players = Vector.fill(TeamInfo.PlayerSlots)(playerV8(r))
    TeamInfo(
      teamNumber = teamNumber,
      teamColour = teamColour,
      score = score,
      goalColour = None,
      penaltyShot = Some(penaltyShot),
      singleShots = Some(singleShots),
      coachMessage = Some(coachMessage),
      coach = Some(coach),
      players = players
    )
  }

  private def playerV8(r: Reader): PlayerInfo = {
    val penalty = Penalty.fromCode(r.u8())
    PlayerInfo(penalty, r.u8())
  }

  private def decodeV7(bytes: Array[Byte]): Either[GameControllerError, GameControlData] = {
    val r = new Reader(bytes, VersionOffset + V7VersionBytes)
    val playersPerTeam = r.u8()
    val gameState = GameState.fromCode(r.u8())
    val firstHalf = r.u8()
    val kickOffTeam = KickOffTeam.fromCode(r.u8())
    val secondaryGameState = SecondaryGameState.fromCode(r.u8())
    val dropInTeam = TeamColour.fromCode(r.u8())
    val dropInTime = r.i16()
    val secsRemaining = r.u32()
    val team0 = teamV7(r)
    val team1 = teamV7(r)
    flag("firstHalf", firstHalf).map { half =>
      GameControlData(
        version = GameControlVersion.V7,
        packetNumber = None,
        playersPerTeam = playersPerTeam,
        gameState = gameState,
        firstHalf = half,
        kickOffTeam = kickOffTeam,
        secondaryGameState = secondaryGameState,
        dropInTeam = dropInTeam,
        dropInTime = dropInTime,
        secsRemaining = secsRemaining,
        secondaryTime = None,
        team0 = team0,
        team1 = team1
      )
    }
  }

  private def teamV7(r: Reader): TeamInfo = {
    val teamNumber = r.u8()
    val teamColour = TeamColour.fromCode(r.u8())
    val goalColour = GoalColour.fromCode(r.u8())
    val score = r.u8()
    val players = Vector.fill(TeamInfo.PlayerSlots) {
      val penalty = Penalty.fromCode(r.u16())
      PlayerInfo(penalty, r.u16())
    }
    TeamInfo(
      teamNumber = teamNumber,
      teamColour = teamColour,
      score = score,
      goalColour = Some(goalColour),
      penaltyShot = None,
      singleShots = None,
      coachMessage = None,
      coach = None,
      players = players
    )
  }

  // Reading 2 as "true" would be a guess; only the two values the GameController writes are accepted.
  private def flag(field: String, value: Int): Either[GameControllerError, Boolean] =
    value match {
      case 0 => Right(false)
      case 1 => Right(true)
      case other => Left(InvalidField(field, other.toLong))
    }

  private def validate(d: GameControlData): Option[GameControllerError] = {
    val v = d.version.number
    val common = List(
      u8Range(v, "playersPerTeam", d.playersPerTeam.toLong),
      u8Range(v, "gameState", d.gameState.code.toLong),
      u8Range(v, "kickOffTeam", d.kickOffTeam.code.toLong),
      u8Range(v, "secondaryGameState", d.secondaryGameState.code.toLong),
      u8Range(v, "dropInTeam", d.dropInTeam.code.toLong),
      range(v, "dropInTime", d.dropInTime.toLong, I16Min, I16Max)
    )
    val specific = d.version match {
      case GameControlVersion.V8 =>
        List(
          required(v, "packetNumber", d.packetNumber),
          d.packetNumber.flatMap(n => u8Range(v, "packetNumber", n.toLong)),
          range(v, "secsRemaining", d.secsRemaining, I16Min, I16Max),
          required(v, "secondaryTime", d.secondaryTime),
          d.secondaryTime.flatMap(t => range(v, "secondaryTime", t.toLong, I16Min, I16Max))
        )
      case GameControlVersion.V7 =>
        List(
          absent(v, "packetNumber", d.packetNumber),
          range(v, "secsRemaining", d.secsRemaining, 0L, U32Max),
          absent(v, "secondaryTime", d.secondaryTime)
        )
    }
    val teams = validateTeam(d.version, "team0", d.team0) ++ validateTeam(d.version, "team1", d.team1)
    firstError(common ++ specific ++ teams: _*)
  }

  private def validateTeam(
      version: GameControlVersion,
      name: String,
      t: TeamInfo
  ): List[Option[GameControllerError]] = {
    val v = version.number
    val common = List(
      u8Range(v, s"$name.teamNumber", t.teamNumber.toLong),
      u8Range(v, s"$name.teamColour", t.teamColour.code.toLong),
      u8Range(v, s"$name.score", t.score.toLong),
      length(s"$name.players", TeamInfo.PlayerSlots, t.players.size)
    )
    version match {
      case GameControlVersion.V8 =>
        common ++ List(
          absent(v, s"$name.goalColour", t.goalColour),
          required(v, s"$name.penaltyShot", t.penaltyShot),
          t.penaltyShot.flatMap(p => u8Range(v, s"$name.penaltyShot", p.toLong)),
          required(v, s"$name.singleShots", t.singleShots),
          t.singleShots.flatMap(s => range(v, s"$name.singleShots", s.toLong, 0L, U16Max)),
          required(v, s"$name.coachMessage", t.coachMessage),
          t.coachMessage.flatMap(m => length(s"$name.coachMessage", TeamInfo.CoachMessageBytes, m.length)),
          required(v, s"$name.coach", t.coach)
        ) ++ t.coach.toList.flatMap(validatePlayer(v, s"$name.coach", U8Max, _)) ++ validatePlayers(v, name, U8Max, t)
      case GameControlVersion.V7 =>
        common ++ List(
          required(v, s"$name.goalColour", t.goalColour),
          t.goalColour.flatMap(g => u8Range(v, s"$name.goalColour", g.code.toLong)),
          absent(v, s"$name.penaltyShot", t.penaltyShot),
          absent(v, s"$name.singleShots", t.singleShots),
          absent(v, s"$name.coachMessage", t.coachMessage),
          absent(v, s"$name.coach", t.coach)
        ) ++ validatePlayers(v, name, U16Max, t)
    }
  }

  private def validatePlayers(v: Int, team: String, max: Long, t: TeamInfo): List[Option[GameControllerError]] =
    t.players.zipWithIndex.toList.flatMap { case (p, i) => validatePlayer(v, s"$team.players[$i]", max, p) }

  private def validatePlayer(v: Int, name: String, max: Long, p: PlayerInfo): List[Option[GameControllerError]] =
    List(
      range(v, s"$name.penalty", p.penalty.code.toLong, 0L, max),
      range(v, s"$name.secsTillUnpenalised", p.secsTillUnpenalised.toLong, 0L, max)
    )

  private def firstError(checks: Option[GameControllerError]*): Option[GameControllerError] =
    checks.collectFirst { case Some(error) => error }

  private def range(v: Int, field: String, value: Long, min: Long, max: Long): Option[GameControllerError] =
    if (value < min || value > max) Some(OutOfRange(v, field, value, min, max)) else None

  private def u8Range(v: Int, field: String, value: Long): Option[GameControllerError] =
    range(v, field, value, 0L, U8Max)

  private def required(v: Int, field: String, value: Option[Any]): Option[GameControllerError] =
    if (value.isEmpty) Some(MissingField(v, field)) else None

  private def absent(v: Int, field: String, value: Option[Any]): Option[GameControllerError] =
    if (value.isDefined) Some(UnexpectedField(v, field)) else None

  private def length(field: String, expected: Int, found: Int): Option[GameControllerError] =
    if (found != expected) Some(WrongLength(field, expected, found)) else None

  // The writers run only after validate, so every Option is present and every value fits.

  private def writeV8(d: GameControlData): Array[Byte] = {
    val w = new Writer(GameControlVersion.V8.packetBytes)
    w.raw(ControlHeaderBytes)
    w.u8(GameControlVersion.V8.number)
    w.u8(d.packetNumber.getOrElse(0))
    writeCommon(w, d)
    w.u16(d.secsRemaining.toInt)
    w.u16(d.secondaryTime.getOrElse(0))
    List(d.team0, d.team1).foreach { t =>
      w.u8(t.teamNumber)
      w.u8(t.teamColour.code)
      w.u8(t.score)
      w.u8(t.penaltyShot.getOrElse(0))
      w.u16(t.singleShots.getOrElse(0))
      t.coachMessage.foreach(m => w.raw(m.toArray))
      (t.coach.toList ++ t.players).foreach { p =>
        w.u8(p.penalty.code)
        w.u8(p.secsTillUnpenalised)
      }
    }
    w.out
  }

  private def writeV7(d: GameControlData): Array[Byte] = {
    val w = new Writer(GameControlVersion.V7.packetBytes)
    w.raw(ControlHeaderBytes)
    w.u32(GameControlVersion.V7.number.toLong)
    writeCommon(w, d)
    w.u32(d.secsRemaining)
    List(d.team0, d.team1).foreach { t =>
      w.u8(t.teamNumber)
      w.u8(t.teamColour.code)
      w.u8(t.goalColour.fold(0)(_.code))
      w.u8(t.score)
      t.players.foreach { p =>
        w.u16(p.penalty.code)
        w.u16(p.secsTillUnpenalised)
      }
    }
    w.out
  }

  private def writeCommon(w: Writer, d: GameControlData): Unit = {
    w.u8(d.playersPerTeam)
    w.u8(d.gameState.code)
    w.u8(if (d.firstHalf) 1 else 0)
    w.u8(d.kickOffTeam.code)
    w.u8(d.secondaryGameState.code)
    w.u8(d.dropInTeam.code)
    w.u16(d.dropInTime)
  }

  private def u8(bytes: Array[Byte], at: Int): Int = bytes(at) & 0xff

  private def slice(bytes: Array[Byte], from: Int, until: Int): ArraySeq[Byte] =
    ArraySeq.unsafeWrapArray(java.util.Arrays.copyOfRange(bytes, from, math.min(until, bytes.length)))

  /** Little-endian reads from a position; callers check the size first, so reads stay in bounds. */
  private final class Reader(data: Array[Byte], private var position: Int) {
    def u8(): Int = {
      val value = data(position) & 0xff
      position += 1
      value
    }
    def u16(): Int = {
      val low = u8()
      low | (u8() << 8)
    }
    def i16(): Int = u16().toShort.toInt
    def u32(): Long = {
      val low = u16().toLong
      low | (u16().toLong << 16)
    }
    def take(n: Int): ArraySeq[Byte] = {
      val copy = java.util.Arrays.copyOfRange(data, position, position + n)
      position += n
      ArraySeq.unsafeWrapArray(copy)
    }
  }

  /** Little-endian writes into a buffer of the packet's exact size; i16 values go out as their two's complement. */
  private final class Writer(size: Int) {
    val out: Array[Byte] = new Array[Byte](size)
    private var position = 0
    def u8(value: Int): Unit = {
      out(position) = value.toByte
      position += 1
    }
    def u16(value: Int): Unit = {
      u8(value)
      u8(value >> 8)
    }
    def u32(value: Long): Unit = {
      u16((value & 0xffff).toInt)
      u16(((value >>> 16) & 0xffff).toInt)
    }
    def raw(bytes: Array[Byte]): Unit = {
      System.arraycopy(bytes, 0, out, position, bytes.length)
      position += bytes.length
    }
  }
}
