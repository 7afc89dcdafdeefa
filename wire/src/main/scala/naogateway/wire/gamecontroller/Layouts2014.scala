package naogateway.wire.gamecontroller

import naogateway.wire.gamecontroller.GameControllerCodec.{
  ControlHeaderBytes,
  V7VersionBytes,
  VersionOffset,
  firstError,
  flag,
  length,
  range,
  u8Range
}
import naogateway.wire.gamecontroller.GameControllerError._

/** The layouts of versions 8 and 7, the 2014 GameController's (docs/protocol.md §10.1, §10.2), for
  * [[GameControllerCodec]], which checks the header, the version and the size before these run. Writers run only after
  * their validation passed.
  */
private[gamecontroller] object Layouts2014 {

  private val U8Max = 0xffL
  private val U16Max = 0xffffL
  private val U32Max = 0xffffffffL
  private val I16Min = Short.MinValue.toLong
  private val I16Max = Short.MaxValue.toLong

  def decodeV8(bytes: Array[Byte]): Either[GameControllerError, ControlData2014] = {
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

  def decodeV7(bytes: Array[Byte]): Either[GameControllerError, ControlData2014] = {
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
  def validate(d: ControlData2014): Option[GameControllerError] = {
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

  private def required(v: Int, field: String, value: Option[Any]): Option[GameControllerError] =
    if (value.isEmpty) Some(MissingField(v, field)) else None

  private def absent(v: Int, field: String, value: Option[Any]): Option[GameControllerError] =
    if (value.isDefined) Some(UnexpectedField(v, field)) else None

  def writeV8(d: ControlData2014): Array[Byte] = {
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

  def writeV7(d: ControlData2014): Array[Byte] = {
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
}
