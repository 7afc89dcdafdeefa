package naogateway.wire.gamecontroller

import naogateway.wire.gamecontroller.GameControllerCodec.{
  ControlHeaderBytes,
  VersionOffset,
  firstError,
  fits,
  flag,
  length,
  writeVersion
}
import naogateway.wire.gamecontroller.GameControllerError._
import naogateway.wire.gamecontroller.Width.{I16, U16, U8}

/** Where the two layouts of the 2014 GameController differ (docs/protocol.md §10.1, §10.2); everything else they share,
  * in the same order. One decoder, one validation and one writer read this table, so the differences between versions 8
  * and 7 are the rows below and nothing else.
  *
  * @param packetNumber
  *   a u8 packet number follows the version field
  * @param secsRemaining
  *   the width of `secsRemaining`
  * @param secondaryTime
  *   an i16 `secondaryTime` follows `secsRemaining`
  * @param goalColour
  *   each team has a u8 `goalColour` after its colour
  * @param shotsAndCoach
  *   each team has `penaltyShot`, `singleShots`, the coach's message and the coach's entry after its score
  * @param playerField
  *   the width of both fields of a player's entry
  */
private[gamecontroller] final case class Layout2014(
    version: GameControlVersion,
    packetNumber: Boolean,
    secsRemaining: Width,
    secondaryTime: Boolean,
    goalColour: Boolean,
    shotsAndCoach: Boolean,
    playerField: Width
)

/** The layouts of versions 8 and 7, the 2014 GameController's, for [[GameControllerCodec]], which checks the header,
  * the version and the size before these run. Writers run only after their validation passed.
  */
private[gamecontroller] object Layouts2014 {

  /** Version 8: a packet number and a secondary clock, i16 seconds, the coach, one byte a player field. */
  val V8: Layout2014 = Layout2014(
    GameControlVersion.V8,
    packetNumber = true,
    secsRemaining = I16,
    secondaryTime = true,
    goalColour = false,
    shotsAndCoach = true,
    playerField = U8
  )

  /** Version 7: neither packet number nor secondary clock, u32 seconds, a goal colour, two bytes a player field. */
  val V7: Layout2014 = Layout2014(
    GameControlVersion.V7,
    packetNumber = false,
    secsRemaining = Width.U32,
    secondaryTime = false,
    goalColour = true,
    shotsAndCoach = false,
    playerField = U16
  )

  /** The layout of a 2014 version, if `version` is one. */
  def of(version: GameControlVersion): Option[Layout2014] = Seq(V8, V7).find(_.version == version)

  def decode(layout: Layout2014, bytes: Array[Byte]): Either[GameControllerError, ControlData2014] = {
    val r = new LeReader(bytes, VersionOffset + layout.version.versionBytes)
    val packetNumber = when(layout.packetNumber)(r.u8())
    val playersPerTeam = r.u8()
    val gameState = GameState.fromCode(r.u8())
    val firstHalf = r.u8()
    val kickOffTeam = KickOffTeam.fromCode(r.u8())
    val secondaryGameState = SecondaryGameState.fromCode(r.u8())
    val dropInTeam = TeamColour.fromCode(r.u8())
    val dropInTime = r.i16()
    val secsRemaining = layout.secsRemaining.read(r)
    val secondaryTime = when(layout.secondaryTime)(r.i16())
    val team0 = team(layout, r)
    val team1 = team(layout, r)
    flag("firstHalf", firstHalf).map { half =>
      ControlData2014(
        version = layout.version,
        packetNumber = packetNumber,
        playersPerTeam = playersPerTeam,
        gameState = gameState,
        firstHalf = half,
        kickOffTeam = kickOffTeam,
        secondaryGameState = secondaryGameState,
        dropInTeam = dropInTeam,
        dropInTime = dropInTime,
        secsRemaining = secsRemaining,
        secondaryTime = secondaryTime,
        team0 = team0,
        team1 = team1
      )
    }
  }

  private def team(layout: Layout2014, r: LeReader): TeamInfo = {
    val teamNumber = r.u8()
    val teamColour = TeamColour.fromCode(r.u8())
    val goalColour = when(layout.goalColour)(GoalColour.fromCode(r.u8()))
    val score = r.u8()
    val penaltyShot = when(layout.shotsAndCoach)(r.u8())
    val singleShots = when(layout.shotsAndCoach)(r.u16())
    val coachMessage = when(layout.shotsAndCoach)(r.take(TeamInfo.CoachMessageBytes))
    val coach = when(layout.shotsAndCoach)(player(layout, r))
    val players = Vector.fill(TeamInfo.PlayerSlots)(player(layout, r))
    TeamInfo(
      teamNumber = teamNumber,
      teamColour = teamColour,
      score = score,
      goalColour = goalColour,
      penaltyShot = penaltyShot,
      singleShots = singleShots,
      coachMessage = coachMessage,
      coach = coach,
      players = players
    )
  }

  private def player(layout: Layout2014, r: LeReader): PlayerInfo = {
    val penalty = Penalty.fromCode(layout.playerField.read(r).toInt)
    PlayerInfo(penalty, layout.playerField.read(r).toInt)
  }

  private def when[A](present: Boolean)(read: => A): Option[A] = if (present) Some(read) else None

  // Reading 2 as "true" would be a guess; only the two values the GameController writes are accepted.
  def validate(layout: Layout2014, d: ControlData2014): Option[GameControllerError] = {
    val v = layout.version.number
    val top = List(
      fits(v, "playersPerTeam", d.playersPerTeam.toLong, U8),
      fits(v, "gameState", d.gameState.code.toLong, U8),
      fits(v, "kickOffTeam", d.kickOffTeam.code.toLong, U8),
      fits(v, "secondaryGameState", d.secondaryGameState.code.toLong, U8),
      fits(v, "dropInTeam", d.dropInTeam.code.toLong, U8),
      fits(v, "dropInTime", d.dropInTime.toLong, I16)
    ) ++
      field(v, layout.packetNumber, "packetNumber", d.packetNumber)(n => List(fits(v, "packetNumber", n.toLong, U8))) ++
      List(fits(v, "secsRemaining", d.secsRemaining, layout.secsRemaining)) ++
      field(v, layout.secondaryTime, "secondaryTime", d.secondaryTime)(t =>
        List(fits(v, "secondaryTime", t.toLong, I16)))
    firstError(top ++ validateTeam(layout, "team0", d.team0) ++ validateTeam(layout, "team1", d.team1): _*)
  }

  private def validateTeam(layout: Layout2014, name: String, t: TeamInfo): List[Option[GameControllerError]] = {
    val v = layout.version.number
    val extras = layout.shotsAndCoach
    List(
      fits(v, s"$name.teamNumber", t.teamNumber.toLong, U8),
      fits(v, s"$name.teamColour", t.teamColour.code.toLong, U8),
      fits(v, s"$name.score", t.score.toLong, U8),
      length(s"$name.players", TeamInfo.PlayerSlots, t.players.size)
    ) ++
      field(v, layout.goalColour, s"$name.goalColour", t.goalColour)(g =>
        List(fits(v, s"$name.goalColour", g.code.toLong, U8))) ++
      field(v, extras, s"$name.penaltyShot", t.penaltyShot)(p => List(fits(v, s"$name.penaltyShot", p.toLong, U8))) ++
      field(v, extras, s"$name.singleShots", t.singleShots)(s => List(fits(v, s"$name.singleShots", s.toLong, U16))) ++
      field(v, extras, s"$name.coachMessage", t.coachMessage)(m =>
        List(length(s"$name.coachMessage", TeamInfo.CoachMessageBytes, m.length))) ++
      field(v, extras, s"$name.coach", t.coach)(validatePlayer(layout, s"$name.coach", _)) ++
      t.players.zipWithIndex.toList.flatMap { case (p, i) => validatePlayer(layout, s"$name.players[$i]", p) }
  }

  private def validatePlayer(layout: Layout2014, name: String, p: PlayerInfo): List[Option[GameControllerError]] = {
    val v = layout.version.number
    List(
      fits(v, s"$name.penalty", p.penalty.code.toLong, layout.playerField),
      fits(v, s"$name.secsTillUnpenalised", p.secsTillUnpenalised.toLong, layout.playerField)
    )
  }

  /** A field one layout has and the other lacks: present and valid where the layout has it, absent where it lacks it.
    */
  private def field[A](v: Int, inLayout: Boolean, name: String, value: Option[A])(
      check: A => List[Option[GameControllerError]]
  ): List[Option[GameControllerError]] =
    if (!inLayout) List(value.map(_ => UnexpectedField(v, name)))
    else if (value.isEmpty) List(Some(MissingField(v, name)))
    else value.toList.flatMap(check)

  // Validation made every Option present exactly where the layout has its field, so writing what is present writes the
  // layout.
  def write(layout: Layout2014, d: ControlData2014): Array[Byte] = {
    val w = new LeWriter(layout.version.packetBytes)
    w.raw(ControlHeaderBytes)
    writeVersion(w, layout.version)
    d.packetNumber.foreach(w.u8)
    w.u8(d.playersPerTeam)
    w.u8(d.gameState.code)
    w.flag(d.firstHalf)
    w.u8(d.kickOffTeam.code)
    w.u8(d.secondaryGameState.code)
    w.u8(d.dropInTeam.code)
    w.u16(d.dropInTime)
    layout.secsRemaining.write(w, d.secsRemaining)
    d.secondaryTime.foreach(w.u16)
    List(d.team0, d.team1).foreach { t =>
      w.u8(t.teamNumber)
      w.u8(t.teamColour.code)
      t.goalColour.foreach(g => w.u8(g.code))
      w.u8(t.score)
      t.penaltyShot.foreach(w.u8)
      t.singleShots.foreach(w.u16)
      t.coachMessage.foreach(m => w.raw(m.toArray))
      (t.coach.toList ++ t.players).foreach { p =>
        layout.playerField.write(w, p.penalty.code.toLong)
        layout.playerField.write(w, p.secsTillUnpenalised.toLong)
      }
    }
    w.out
  }
}
