package naogateway.wire.gamecontroller

import java.nio.charset.StandardCharsets

import scala.collection.immutable.ArraySeq

import naogateway.wire.gamecontroller.GameControllerError._

/**
 * Encoder and decoder of GameController packets (docs/protocol.md §10): the `RGme` control packet in versions 19
 * (198 bytes), 12 (688 bytes), 8 (158 bytes) and 7 (116 bytes), the same version-19 layout under `RGTD` (the true
 * state a monitor gets), and the `RGrt` return packet in versions 4 (32 bytes) and 2 (8 bytes). All numbers are
 * little-endian. Pure functions; decoding never throws and never guesses: a packet must have a known header, a known
 * version and exactly that version's size, or it is refused with a typed error.
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

  /** The return-packet version robots send to the version-19 GameController (its status message). */
  val StatusVersion: Int = 4

  /** Exact size of a version-4 return packet. */
  val StatusPacketBytes: Int = 32

  private val HeaderBytes = 4
  private val VersionOffset = 4
  private val V7VersionBytes = 4
  private val ControlHeaderBytes = ControlHeader.getBytes(StandardCharsets.US_ASCII)
  private val TrueDataHeaderBytes = TrueDataHeader.getBytes(StandardCharsets.US_ASCII)
  private val ReturnHeaderBytes = ReturnHeader.getBytes(StandardCharsets.US_ASCII)

  private val U8Max = 0xffL
  private val U16Max = 0xffffL
  private val U32Max = 0xffffffffL
  private val I16Min = Short.MinValue.toLong
  private val I16Max = Short.MaxValue.toLong

  /**
   * Decodes a control packet. The version decides the layout, and each version's field has its own width, all
   * starting at byte 4: byte 4 = 19 or 8 is that version (a u8 field, a packet number follows); bytes 4–5 must read
   * the u16 12 for version 12; bytes 4–7 the u32 7 for version 7. Then the size must be exactly the version's.
   */
  def decodeControl(bytes: Array[Byte]): Either[GameControllerError, GameControlData] =
    for {
      _ <- checkHeader(bytes, ControlHeaderBytes, ControlHeader)
      version <- controlVersion(bytes, ControlHeader)
      _ <- checkSize(bytes, ControlHeader, version.number, version.packetBytes)
      data <- version match {
        case GameControlVersion.V19 => ModernLayouts.decodeV19(bytes)
        case GameControlVersion.V12 => ModernLayouts.decodeV12(bytes)
        case GameControlVersion.V8  => decodeV8(bytes)
        case GameControlVersion.V7  => decodeV7(bytes)
      }
    } yield data

  /** Encodes a control packet in its version's layout, refusing fields that do not fit that layout. */
  def encodeControl(data: GameControlData): Either[GameControllerError, Array[Byte]] =
    data match {
      case d: ControlData2014 if d.version != GameControlVersion.V8 && d.version != GameControlVersion.V7 =>
        Left(InvalidField("version", d.version.number.toLong))
      case d: ControlData2014 =>
        validate(d).toLeft(d.version match {
          case GameControlVersion.V7 => writeV7(d)
          case _                     => writeV8(d)
        })
      case d: HlControlData  => ModernLayouts.validateV12(d).toLeft(ModernLayouts.writeV12(d))
      case d: HslControlData => ModernLayouts.validateV19(d).toLeft(ModernLayouts.writeV19(d, ControlHeaderBytes))
    }

  /** Decodes the true game state a version-19 GameController sends its monitors: `RGTD`, version 19, 198 bytes. */
  def decodeTrueData(bytes: Array[Byte]): Either[GameControllerError, HslControlData] =
    for {
      _ <- checkHeader(bytes, TrueDataHeaderBytes, TrueDataHeader)
      version <- controlVersion(bytes, TrueDataHeader)
      _ <-
        if (version == GameControlVersion.V19) Right(())
        else Left(UnknownVersion(TrueDataHeader, slice(bytes, VersionOffset, VersionOffset + version.versionBytes)))
      _ <- checkSize(bytes, TrueDataHeader, version.number, version.packetBytes)
      data <- ModernLayouts.decodeV19(bytes)
    } yield data

  /** Encodes the true game state as a version-19 GameController sends it to a monitor (`RGTD`). */
  def encodeTrueData(data: HslControlData): Either[GameControllerError, Array[Byte]] =
    ModernLayouts.validateV19(data).toLeft(ModernLayouts.writeV19(data, TrueDataHeaderBytes))

  /** Decodes a version-2 return packet (exactly 8 bytes). */
  def decodeReturn(bytes: Array[Byte]): Either[GameControllerError, ReturnData] =
    for {
      _ <- returnVersion(bytes, ReturnVersion)
      _ <- checkSize(bytes, ReturnHeader, ReturnVersion, ReturnPacketBytes)
    } yield ReturnData(u8(bytes, 5), u8(bytes, 6), ReturnMessage.fromCode(u8(bytes, 7)))

  /**
   * Decodes a version-4 return packet (exactly 32 bytes). Like the GameController, it refuses a `fallen` byte other
   * than 0 or 1 and a coordinate that is not a number (NaN).
   */
  def decodeStatus(bytes: Array[Byte]): Either[GameControllerError, ReturnStatus] =
    for {
      _ <- returnVersion(bytes, StatusVersion)
      _ <- checkSize(bytes, ReturnHeader, StatusVersion, StatusPacketBytes)
      r = new LeReader(bytes, VersionOffset + 1)
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
      val w = new LeWriter(ReturnPacketBytes)
      w.raw(ReturnHeaderBytes)
      w.u8(ReturnVersion)
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
      val w = new LeWriter(StatusPacketBytes)
      w.raw(ReturnHeaderBytes)
      w.u8(StatusVersion)
      w.u8(data.player)
      w.u8(data.team)
      w.flag(data.fallen)
      floats.foreach(w.f32)
      w.out
    }
  }

  /** First four bytes of a monitor's request for the true game state (to UDP 3636 of the version-19 GameController). */
  val MonitorRequestHeader: String = "RGTr"

  /** The monitor request: `RGTr` and version 0, 5 bytes. */
  def monitorRequest: Array[Byte] = MonitorRequestHeader.getBytes(StandardCharsets.US_ASCII) :+ 0.toByte

  /** Bytes of the IPv4 address before each status message the GameController forwards to a monitor (UDP 3940). */
  val ForwardPrefixBytes: Int = 4

  /**
   * Decodes a status message forwarded to a monitor: the IPv4 address of the robot that sent it, then its `RGrt`
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

  private def returnVersion(bytes: Array[Byte], version: Int): Either[GameControllerError, Unit] =
    for {
      _ <- checkHeader(bytes, ReturnHeaderBytes, ReturnHeader)
      _ <-
        if (bytes.length <= VersionOffset) Left(TooShort(VersionOffset + 1, bytes.length))
        else if (u8(bytes, VersionOffset) != version)
          Left(UnknownVersion(ReturnHeader, slice(bytes, VersionOffset, VersionOffset + 1)))
        else Right(())
    } yield ()

  private def checkHeader(bytes: Array[Byte], header: Array[Byte], name: String): Either[GameControllerError, Unit] =
    if (bytes.length < HeaderBytes) Left(TooShort(HeaderBytes, bytes.length))
    else if (java.util.Arrays.equals(bytes, 0, HeaderBytes, header, 0, HeaderBytes)) Right(())
    else Left(WrongHeader(name, slice(bytes, 0, HeaderBytes)))

  private def controlVersion(bytes: Array[Byte], header: String): Either[GameControllerError, GameControlVersion] = {
    def unknown = Left(UnknownVersion(header, slice(bytes, VersionOffset, VersionOffset + V7VersionBytes)))
    if (bytes.length <= VersionOffset) Left(TooShort(VersionOffset + 1, bytes.length))
    else
      u8(bytes, VersionOffset) match {
        case 19 => Right(GameControlVersion.V19)
        case 8  => Right(GameControlVersion.V8)
        case 12 =>
          if (bytes.length < VersionOffset + 2) Left(TooShort(VersionOffset + 2, bytes.length))
          else if (u8(bytes, VersionOffset + 1) == 0) Right(GameControlVersion.V12)
          else unknown
        case 7 =>
          if (bytes.length < VersionOffset + V7VersionBytes) Left(TooShort(VersionOffset + V7VersionBytes, bytes.length))
          else if (new LeReader(bytes, VersionOffset).u32() == GameControlVersion.V7.number.toLong) Right(GameControlVersion.V7)
          else unknown
        case _ => unknown
      }
  }

  private[gamecontroller] def checkSize(
      bytes: Array[Byte],
      header: String,
      version: Int,
      size: Int
  ): Either[GameControllerError, Unit] =
    if (bytes.length == size) Right(()) else Left(WrongSize(header, version, size, bytes.length))

  private def decodeV8(bytes: Array[Byte]): Either[GameControllerError, ControlData2014] = {
    val r = new LeReader(bytes, VersionOffset + 1)
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
      ControlData2014(
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

  private def teamV8(r: LeReader): TeamInfo = {
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

  private def playerV8(r: LeReader): PlayerInfo = {
    val penalty = Penalty.fromCode(r.u8())
    PlayerInfo(penalty, r.u8())
  }

  private def decodeV7(bytes: Array[Byte]): Either[GameControllerError, ControlData2014] = {
    val r = new LeReader(bytes, VersionOffset + V7VersionBytes)
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
      ControlData2014(
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

  private def teamV7(r: LeReader): TeamInfo = {
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
  private[gamecontroller] def flag(field: String, value: Int): Either[GameControllerError, Boolean] =
    value match {
      case 0 => Right(false)
      case 1 => Right(true)
      case other => Left(InvalidField(field, other.toLong))
    }

  private def validate(d: ControlData2014): Option[GameControllerError] = {
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
      case _ =>
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
      case _ =>
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

  private[gamecontroller] def firstError(checks: Option[GameControllerError]*): Option[GameControllerError] =
    checks.collectFirst { case Some(error) => error }

  private[gamecontroller] def range(v: Int, field: String, value: Long, min: Long, max: Long): Option[GameControllerError] =
    if (value < min || value > max) Some(OutOfRange(v, field, value, min, max)) else None

  private[gamecontroller] def u8Range(v: Int, field: String, value: Long): Option[GameControllerError] =
    range(v, field, value, 0L, U8Max)

  private def required(v: Int, field: String, value: Option[Any]): Option[GameControllerError] =
    if (value.isEmpty) Some(MissingField(v, field)) else None

  private def absent(v: Int, field: String, value: Option[Any]): Option[GameControllerError] =
    if (value.isDefined) Some(UnexpectedField(v, field)) else None

  private[gamecontroller] def length(field: String, expected: Int, found: Int): Option[GameControllerError] =
    if (found != expected) Some(WrongLength(field, expected, found)) else None

  // The writers run only after validate, so every Option is present and every value fits.

  private def writeV8(d: ControlData2014): Array[Byte] = {
    val w = new LeWriter(GameControlVersion.V8.packetBytes)
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

  private def writeV7(d: ControlData2014): Array[Byte] = {
    val w = new LeWriter(GameControlVersion.V7.packetBytes)
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

  private def writeCommon(w: LeWriter, d: ControlData2014): Unit = {
    w.u8(d.playersPerTeam)
    w.u8(d.gameState.code)
    w.u8(if (d.firstHalf) 1 else 0)
    w.u8(d.kickOffTeam.code)
    w.u8(d.secondaryGameState.code)
    w.u8(d.dropInTeam.code)
    w.u16(d.dropInTime)
  }

  private[gamecontroller] def u8(bytes: Array[Byte], at: Int): Int = bytes(at) & 0xff

  private[gamecontroller] def slice(bytes: Array[Byte], from: Int, until: Int): ArraySeq[Byte] =
    ArraySeq.unsafeWrapArray(java.util.Arrays.copyOfRange(bytes, from, math.min(until, bytes.length)))
}
