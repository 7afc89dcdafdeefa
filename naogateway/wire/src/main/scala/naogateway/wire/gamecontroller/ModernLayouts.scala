package naogateway.wire.gamecontroller

import naogateway.wire.gamecontroller.GameControllerCodec.{
  ControlHeaderBytes,
  VersionOffset,
  firstError,
  fits,
  flag,
  length,
  range,
  u8Range,
  writeVersion
}
import naogateway.wire.gamecontroller.Width.{I16, U16}

/** The layouts of versions 20, 19 and 12 (docs/protocol.md §10.2, §10.3), for [[GameControllerCodec]], which checks the
  * header, the version and the size before these run. Writers run only after their validation passed.
  */
private[gamecontroller] object ModernLayouts {

  private val KickingTeamNone = 255
  private val SecondaryStateInfoBytes = 4

  private def teamOrNone(code: Int): Option[Int] = if (code == KickingTeamNone) None else Some(code)

  /** Bytes of the header versions 18, 19 and 20 share, from `RGme` to `secondaryTime`. */
  val SharedHeaderBytes: Int = 18

  /** Reads the shared header; the caller has checked that `bytes` holds at least [[SharedHeaderBytes]]. */
  def readHeader(bytes: Array[Byte]): Either[GameControllerError, SharedHeader] = {
    val r = new LeReader(bytes, VersionOffset)
    val version = r.u8()
    val packetNumber = r.u8()
    val playersPerTeam = r.u8()
    val competitionType = CompetitionType.fromCode(r.u8())
    val stopped = r.u8()
    val gamePhase = GamePhase.fromCode(r.u8())
    val state = GameState.fromCode(r.u8())
    val setPlay = SetPlay.fromCode(r.u8())
    val firstHalf = r.u8()
    val kickingTeam = teamOrNone(r.u8())
    val secsRemaining = r.i16()
    val secondaryTime = r.i16()
    for {
      s <- flag("stopped", stopped)
      h <- flag("firstHalf", firstHalf)
    } yield SharedHeader(version, bytes.length, packetNumber, playersPerTeam, competitionType, s, gamePhase, state,
      setPlay, h, kickingTeam, secsRemaining.toLong, secondaryTime)
  }

  private def validateHeader(v: Int, d: HslHeaderFields): List[Option[GameControllerError]] = List(
    u8Range(v, "packetNumber", d.packetNumber.toLong),
    u8Range(v, "playersPerTeam", d.playersPerTeam.toLong),
    u8Range(v, "competitionType", d.competitionType.code.toLong),
    u8Range(v, "gamePhase", d.gamePhase.code.toLong),
    u8Range(v, "gameState", d.gameState.code.toLong),
    u8Range(v, "setPlay", d.setPlay.code.toLong),
    d.kickingTeam.flatMap(t => range(v, "kickingTeam", t.toLong, 0L, KickingTeamNone - 1L)),
    fits(v, "secsRemaining", d.secsRemaining, I16),
    fits(v, "secondaryTime", d.secondaryTime.toLong, I16)
  )

  /** The checks of a team entry's fields before its players, in wire order (the same in versions 19 and 20). */
  private def validateTeamHead(v: Int, name: String, number: Int, colour: FieldColour, keeperColour: FieldColour,
      keeper: Int, score: Int, penaltyShot: Int, singleShots: Int, budget: Int, players: Int)
      : List[Option[GameControllerError]] =
    List(
      u8Range(v, s"$name.teamNumber", number.toLong),
      u8Range(v, s"$name.fieldPlayerColour", colour.code.toLong),
      u8Range(v, s"$name.goalkeeperColour", keeperColour.code.toLong),
      u8Range(v, s"$name.goalkeeper", keeper.toLong),
      u8Range(v, s"$name.score", score.toLong),
      u8Range(v, s"$name.penaltyShot", penaltyShot.toLong),
      fits(v, s"$name.singleShots", singleShots.toLong, U16),
      fits(v, s"$name.messageBudget", budget.toLong, U16),
      length(s"$name.players", HslPlayerInfo.Slots, players)
    )

  private def writeHeader(w: LeWriter, header: Array[Byte], version: GameControlVersion, d: HslHeaderFields): Unit = {
    w.raw(header)
    writeVersion(w, version)
    w.u8(d.packetNumber)
    w.u8(d.playersPerTeam)
    w.u8(d.competitionType.code)
    w.flag(d.stopped)
    w.u8(d.gamePhase.code)
    w.u8(d.gameState.code)
    w.u8(d.setPlay.code)
    w.flag(d.firstHalf)
    w.u8(d.kickingTeam.getOrElse(KickingTeamNone))
    w.u16(d.secsRemaining.toInt)
    w.u16(d.secondaryTime)
  }

  /** The fields of a team entry before its players, in wire order (the same in versions 19 and 20). */
  private def writeTeamHead(w: LeWriter, number: Int, colour: FieldColour, keeperColour: FieldColour, keeper: Int,
      score: Int, penaltyShot: Int, singleShots: Int, budget: Int): Unit = {
    w.u8(number)
    w.u8(colour.code)
    w.u8(keeperColour.code)
    w.u8(keeper)
    w.u8(score)
    w.u8(penaltyShot)
    w.u16(singleShots)
    w.u16(budget)
  }

  def decodeV19(bytes: Array[Byte]): Either[GameControllerError, HslControlData] =
    readHeader(bytes).map { h =>
      val r = new LeReader(bytes, SharedHeaderBytes)
      val team0 = teamV19(r)
      val team1 = teamV19(r)
      HslControlData(
        h.packetNumber,
        h.playersPerTeam,
        h.competitionType,
        h.stopped,
        h.gamePhase,
        h.gameState,
        h.setPlay,
        h.firstHalf,
        h.kickingTeam,
        h.secsRemaining,
        h.secondaryTime,
        team0,
        team1
      )
    }

  private def teamV19(r: LeReader): HslTeamInfo = {
    val number = r.u8()
    val fieldColour = FieldColour.fromCode(r.u8())
    val goalkeeperColour = FieldColour.fromCode(r.u8())
    val goalkeeper = r.u8()
    val score = r.u8()
    val penaltyShot = r.u8()
    val singleShots = r.u16()
    val budget = r.u16()
    val players = Vector.fill(HslPlayerInfo.Slots)(HslPlayerInfo(HslPenalty.fromCode(r.u8()), r.u8(), r.u8(), r.u8()))
    HslTeamInfo(number, fieldColour, goalkeeperColour, goalkeeper, score, penaltyShot, singleShots, budget, players)
  }

  def validateV19(d: HslControlData): Option[GameControllerError] = {
    val v = 19
    def team(name: String, t: HslTeamInfo): List[Option[GameControllerError]] =
      validateTeamHead(v, name, t.teamNumber, t.fieldPlayerColour, t.goalkeeperColour, t.goalkeeper, t.score,
        t.penaltyShot, t.singleShots, t.messageBudget, t.players.size) ++ t.players.zipWithIndex.toList.flatMap {
        case (p, i) =>
          val n = s"$name.players[$i]"
          List(
            u8Range(v, s"$n.penalty", p.penalty.code.toLong),
            u8Range(v, s"$n.secsTillUnpenalised", p.secsTillUnpenalised.toLong),
            u8Range(v, s"$n.warnings", p.warnings.toLong),
            u8Range(v, s"$n.cautions", p.cautions.toLong)
          )
      }
    firstError(validateHeader(v, d) ++ team("team0", d.team0) ++ team("team1", d.team1): _*)
  }

  def writeV19(d: HslControlData, header: Array[Byte]): Array[Byte] = {
    val w = new LeWriter(GameControlVersion.V19.packetBytes)
    writeHeader(w, header, GameControlVersion.V19, d)
    List(d.team0, d.team1).foreach { t =>
      writeTeamHead(w, t.teamNumber, t.fieldPlayerColour, t.goalkeeperColour, t.goalkeeper, t.score, t.penaltyShot,
        t.singleShots, t.messageBudget)
      t.players.foreach { p =>
        w.u8(p.penalty.code)
        w.u8(p.secsTillUnpenalised)
        w.u8(p.warnings)
        w.u8(p.cautions)
      }
    }
    w.out
  }

  def decodeV20(bytes: Array[Byte]): Either[GameControllerError, Hsl20ControlData] =
    readHeader(bytes).map { h =>
      val r = new LeReader(bytes, SharedHeaderBytes)
      val team0 = teamV20(r)
      val team1 = teamV20(r)
      Hsl20ControlData(
        h.packetNumber,
        h.playersPerTeam,
        h.competitionType,
        h.stopped,
        h.gamePhase,
        h.gameState,
        h.setPlay,
        h.firstHalf,
        h.kickingTeam,
        h.secsRemaining,
        h.secondaryTime,
        team0,
        team1
      )
    }

  private def teamV20(r: LeReader): Hsl20TeamInfo = {
    val number = r.u8()
    val fieldColour = FieldColour.fromCode(r.u8())
    val goalkeeperColour = FieldColour.fromCode(r.u8())
    val goalkeeper = r.u8()
    val score = r.u8()
    val penaltyShot = r.u8()
    val singleShots = r.u16()
    val budget = r.u16()
    val players = Vector.fill(Hsl20PlayerInfo.Slots)(Hsl20PlayerInfo(Hsl20Penalty.fromCode(r.u8()), r.u8(), r.u8()))
    Hsl20TeamInfo(number, fieldColour, goalkeeperColour, goalkeeper, score, penaltyShot, singleShots, budget, players)
  }

  def validateV20(d: Hsl20ControlData): Option[GameControllerError] = {
    val v = 20
    def team(name: String, t: Hsl20TeamInfo): List[Option[GameControllerError]] =
      validateTeamHead(v, name, t.teamNumber, t.fieldPlayerColour, t.goalkeeperColour, t.goalkeeper, t.score,
        t.penaltyShot, t.singleShots, t.messageBudget, t.players.size) ++ t.players.zipWithIndex.toList.flatMap {
        case (p, i) =>
          val n = s"$name.players[$i]"
          List(
            u8Range(v, s"$n.penalty", p.penalty.code.toLong),
            u8Range(v, s"$n.secsTillUnpenalised", p.secsTillUnpenalised.toLong),
            u8Range(v, s"$n.cautions", p.cautions.toLong)
          )
      }
    firstError(validateHeader(v, d) ++ team("team0", d.team0) ++ team("team1", d.team1): _*)
  }

  def writeV20(d: Hsl20ControlData, header: Array[Byte]): Array[Byte] = {
    val w = new LeWriter(GameControlVersion.V20.packetBytes)
    writeHeader(w, header, GameControlVersion.V20, d)
    List(d.team0, d.team1).foreach { t =>
      writeTeamHead(w, t.teamNumber, t.fieldPlayerColour, t.goalkeeperColour, t.goalkeeper, t.score, t.penaltyShot,
        t.singleShots, t.messageBudget)
      t.players.foreach { p =>
        w.u8(p.penalty.code)
        w.u8(p.secsTillUnpenalised)
        w.u8(p.cautions)
      }
    }
    w.out
  }

  def decodeV12(bytes: Array[Byte]): Either[GameControllerError, HlControlData] = {
    val r = new LeReader(bytes, VersionOffset + GameControlVersion.V12.versionBytes)
    val packetNumber = r.u8()
    val playersPerTeam = r.u8()
    val gameType = HlGameType.fromCode(r.u8())
    val state = GameState.fromCode(r.u8())
    val firstHalf = r.u8()
    val kickOffTeam = teamOrNone(r.u8())
    val secondaryState = HlSecondaryState.fromCode(r.u8())
    val info = r.take(SecondaryStateInfoBytes)
    val dropInTeam = r.u8()
    val dropInTime = r.u16()
    val secsRemaining = r.i16()
    val secondaryTime = r.i16()
    for {
      h <- flag("firstHalf", firstHalf)
      team0 <- teamV12(r, "team0")
      team1 <- teamV12(r, "team1")
    } yield HlControlData(packetNumber, playersPerTeam, gameType, state, h, kickOffTeam, secondaryState, info,
      dropInTeam,
      dropInTime, secsRemaining.toLong, secondaryTime, team0, team1)
  }

  private def playerV12(r: LeReader, name: String): Either[GameControllerError, HlPlayerInfo] = {
    val penalty = HlPenalty.fromCode(r.u8())
    val secs = r.u8()
    val warnings = r.u8()
    val yellow = r.u8()
    val red = r.u8()
    flag(s"$name.goalKeeper", r.u8()).map(HlPlayerInfo(penalty, secs, warnings, yellow, red, _))
  }

  private def teamV12(r: LeReader, name: String): Either[GameControllerError, HlTeamInfo] = {
    val number = r.u8()
    val colour = FieldColour.fromCode(r.u8())
    val score = r.u8()
    val penaltyShot = r.u8()
    val singleShots = r.u16()
    val coachSequence = r.u8()
    val coachMessage = r.take(HlPlayerInfo.CoachMessageBytes)
    // Every entry is read, so the reader stays in step even when one is refused.
    val coach = playerV12(r, s"$name.coach")
    val players = Vector.tabulate(HlPlayerInfo.Slots)(i => playerV12(r, s"$name.players[$i]"))
    for {
      c <- coach
      ps <- players.foldLeft[Either[GameControllerError, Vector[HlPlayerInfo]]](Right(Vector.empty)) { (acc, p) =>
        acc.flatMap(v => p.map(v :+ _))
      }
    } yield HlTeamInfo(number, colour, score, penaltyShot, singleShots, coachSequence, coachMessage, c, ps)
  }

  def validateV12(d: HlControlData): Option[GameControllerError] = {
    val v = 12
    val top = List(
      u8Range(v, "packetNumber", d.packetNumber.toLong),
      u8Range(v, "playersPerTeam", d.playersPerTeam.toLong),
      u8Range(v, "gameType", d.gameType.code.toLong),
      u8Range(v, "gameState", d.gameState.code.toLong),
      d.kickOffTeam.flatMap(t => range(v, "kickOffTeam", t.toLong, 0L, KickingTeamNone - 1L)),
      u8Range(v, "secondaryState", d.secondaryState.code.toLong),
      length("secondaryStateInfo", SecondaryStateInfoBytes, d.secondaryStateInfo.size),
      u8Range(v, "dropInTeam", d.dropInTeam.toLong),
      fits(v, "dropInTime", d.dropInTime.toLong, U16),
      fits(v, "secsRemaining", d.secsRemaining, I16),
      fits(v, "secondaryTime", d.secondaryTime.toLong, I16)
    )
    def player(n: String, p: HlPlayerInfo): List[Option[GameControllerError]] =
      List(
        u8Range(v, s"$n.penalty", p.penalty.code.toLong),
        u8Range(v, s"$n.secsTillUnpenalised", p.secsTillUnpenalised.toLong),
        u8Range(v, s"$n.warnings", p.warnings.toLong),
        u8Range(v, s"$n.yellowCards", p.yellowCards.toLong),
        u8Range(v, s"$n.redCards", p.redCards.toLong)
      )
    def team(name: String, t: HlTeamInfo): List[Option[GameControllerError]] =
      List(
        u8Range(v, s"$name.teamNumber", t.teamNumber.toLong),
        u8Range(v, s"$name.fieldPlayerColour", t.fieldPlayerColour.code.toLong),
        u8Range(v, s"$name.score", t.score.toLong),
        u8Range(v, s"$name.penaltyShot", t.penaltyShot.toLong),
        fits(v, s"$name.singleShots", t.singleShots.toLong, U16),
        u8Range(v, s"$name.coachSequence", t.coachSequence.toLong),
        length(s"$name.coachMessage", HlPlayerInfo.CoachMessageBytes, t.coachMessage.size),
        length(s"$name.players", HlPlayerInfo.Slots, t.players.size)
      ) ++ player(s"$name.coach", t.coach) ++
        t.players.zipWithIndex.toList.flatMap { case (p, i) => player(s"$name.players[$i]", p) }
    firstError(top ++ team("team0", d.team0) ++ team("team1", d.team1): _*)
  }

  def writeV12(d: HlControlData): Array[Byte] = {
    val w = new LeWriter(GameControlVersion.V12.packetBytes)
    w.raw(ControlHeaderBytes)
    writeVersion(w, GameControlVersion.V12)
    w.u8(d.packetNumber)
    w.u8(d.playersPerTeam)
    w.u8(d.gameType.code)
    w.u8(d.gameState.code)
    w.flag(d.firstHalf)
    w.u8(d.kickOffTeam.getOrElse(KickingTeamNone))
    w.u8(d.secondaryState.code)
    w.raw(d.secondaryStateInfo.toArray)
    w.u8(d.dropInTeam)
    w.u16(d.dropInTime)
    w.u16(d.secsRemaining.toInt)
    w.u16(d.secondaryTime)
    def player(p: HlPlayerInfo): Unit = {
      w.u8(p.penalty.code)
      w.u8(p.secsTillUnpenalised)
      w.u8(p.warnings)
      w.u8(p.yellowCards)
      w.u8(p.redCards)
      w.flag(p.goalkeeper)
    }
    List(d.team0, d.team1).foreach { t =>
      w.u8(t.teamNumber)
      w.u8(t.fieldPlayerColour.code)
      w.u8(t.score)
      w.u8(t.penaltyShot)
      w.u16(t.singleShots)
      w.u8(t.coachSequence)
      w.raw(t.coachMessage.toArray)
      player(t.coach)
      t.players.foreach(player)
    }
    w.out
  }
}
