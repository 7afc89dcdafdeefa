package naogateway.wire.gamecontroller

import scala.collection.immutable.ArraySeq

import org.scalacheck.{Arbitrary, Gen}

/** Generators of valid GameController values of every version, with unknown codes mixed in. */
object GameControllerGenerators {

  val u8: Gen[Int] = Gen.choose(0, 0xff)
  val u16: Gen[Int] = Gen.choose(0, 0xffff)
  val i16: Gen[Int] = Gen.choose(Short.MinValue.toInt, Short.MaxValue.toInt)
  val u32: Gen[Long] = Gen.choose(0L, 0xffffffffL)

  // Mostly known values; the rest any code of the field's width, which fromCode turns into the known
  // value or Unknown, so Unknown never carries a known code and round trips stay exact.
  private def coded[A](known: Seq[A], fromCode: Int => A, max: Int): Gen[A] =
    Gen.frequency(3 -> Gen.oneOf(known), 1 -> Gen.choose(0, max).map(fromCode))

  val gameState: Gen[GameState] = coded(GameState.known, GameState.fromCode, 0xff)
  val secondaryGameState: Gen[SecondaryGameState] =
    coded(SecondaryGameState.known, SecondaryGameState.fromCode, 0xff)
  val teamColour: Gen[TeamColour] = coded(TeamColour.known, TeamColour.fromCode, 0xff)
  val kickOffTeam: Gen[KickOffTeam] = coded(KickOffTeam.known, KickOffTeam.fromCode, 0xff)
  val goalColour: Gen[GoalColour] = coded(GoalColour.known, GoalColour.fromCode, 0xff)
  def penalty(max: Int): Gen[Penalty] = coded(Penalty.known, Penalty.fromCode, max)
  val returnMessage: Gen[ReturnMessage] = coded(ReturnMessage.known, ReturnMessage.fromCode, 0xff)

  def player(max: Int): Gen[PlayerInfo] =
    Gen.frequency(
      2 -> Gen.const(PlayerInfo.Unpenalised),
      3 -> (for { p <- penalty(max); s <- Gen.choose(0, max) } yield PlayerInfo(p, s))
    )

  private def players(max: Int): Gen[Vector[PlayerInfo]] =
    Gen.listOfN(TeamInfo.PlayerSlots, player(max)).map(_.toVector)

  val coachMessage: Gen[ArraySeq[Byte]] =
    Gen.listOfN(TeamInfo.CoachMessageBytes, Arbitrary.arbitrary[Byte]).map(ArraySeq.from(_))

  val teamV8: Gen[TeamInfo] = for {
    number <- u8
    colour <- teamColour
    score <- u8
    penaltyShot <- u8
    singleShots <- u16
    message <- coachMessage
    coach <- player(0xff)
    ps <- players(0xff)
  } yield TeamInfo(number, colour, score, None, Some(penaltyShot), Some(singleShots), Some(message), Some(coach), ps)

  val teamV7: Gen[TeamInfo] = for {
    number <- u8
    colour <- teamColour
    goal <- goalColour
    score <- u8
    ps <- players(0xffff)
  } yield TeamInfo(number, colour, score, Some(goal), None, None, None, None, ps)

  val controlV8: Gen[ControlData2014] =
    for {
      packetNumber <- u8
      playersPerTeam <- u8
      state <- gameState
      firstHalf <- Gen.oneOf(true, false)
      kickOff <- kickOffTeam
      secondary <- secondaryGameState
      dropInTeam <- teamColour
      dropInTime <- i16
      secsRemaining <- i16
      secondaryTime <- i16
      team0 <- teamV8
      team1 <- teamV8
    } yield ControlData2014(
      GameControlVersion.V8,
      Some(packetNumber),
      playersPerTeam,
      state,
      firstHalf,
      kickOff,
      secondary,
      dropInTeam,
      dropInTime,
      secsRemaining.toLong,
      Some(secondaryTime),
      team0,
      team1
    )

  val controlV7: Gen[ControlData2014] =
    for {
      playersPerTeam <- u8
      state <- gameState
      firstHalf <- Gen.oneOf(true, false)
      kickOff <- kickOffTeam
      secondary <- secondaryGameState
      dropInTeam <- teamColour
      dropInTime <- i16
      secsRemaining <- u32
      team0 <- teamV7
      team1 <- teamV7
    } yield ControlData2014(
      GameControlVersion.V7,
      None,
      playersPerTeam,
      state,
      firstHalf,
      kickOff,
      secondary,
      dropInTeam,
      dropInTime,
      secsRemaining,
      None,
      team0,
      team1
    )

  private def codes[A](c: WireCodes[A]): Gen[A] = Gen.frequency(3 -> Gen.oneOf(c.known), 1 -> u8.map(c.fromCode))

  /** A team number, or `None` for the wire's 255 (no kicking team, dropped ball). */
  val teamOrNone: Gen[Option[Int]] = Gen.option(Gen.choose(0, 254))

  val hslPlayer: Gen[HslPlayerInfo] = Gen.frequency(
    2 -> Gen.const(HslPlayerInfo.Unpenalised),
    3 -> (for { p <- codes(HslPenalty); s <- u8; w <- u8; c <- u8 } yield HslPlayerInfo(p, s, w, c))
  )

  val teamV19: Gen[HslTeamInfo] = for {
    number <- u8
    colour <- codes(FieldColour)
    keeperColour <- codes(FieldColour)
    keeper <- u8
    score <- u8
    penaltyShot <- u8
    singleShots <- u16
    budget <- u16
    players <- Gen.listOfN(HslPlayerInfo.Slots, hslPlayer)
  } yield HslTeamInfo(number, colour, keeperColour, keeper, score, penaltyShot, singleShots, budget, players.toVector)

  val controlV19: Gen[HslControlData] =
    for {
      packetNumber <- u8
      playersPerTeam <- u8
      competition <- codes(CompetitionType)
      stopped <- Gen.oneOf(true, false)
      phase <- codes(GamePhase)
      state <- gameState
      setPlay <- codes(SetPlay)
      firstHalf <- Gen.oneOf(true, false)
      kicking <- teamOrNone
      secs <- i16
      secondary <- i16
      team0 <- teamV19
      team1 <- teamV19
    } yield HslControlData(packetNumber, playersPerTeam, competition, stopped, phase, state, setPlay, firstHalf,
      kicking,
      secs.toLong, secondary, team0, team1)

  val hsl20Player: Gen[Hsl20PlayerInfo] = Gen.frequency(
    2 -> Gen.const(Hsl20PlayerInfo.Unpenalised),
    3 -> (for { p <- codes(Hsl20Penalty); s <- u8; c <- u8 } yield Hsl20PlayerInfo(p, s, c))
  )

  val teamV20: Gen[Hsl20TeamInfo] =
    for {
      number <- u8
      colour <- codes(FieldColour)
      keeperColour <- codes(FieldColour)
      keeper <- u8
      score <- u8
      penaltyShot <- u8
      singleShots <- u16
      budget <- u16
      players <- Gen.listOfN(Hsl20PlayerInfo.Slots, hsl20Player)
    } yield Hsl20TeamInfo(number, colour, keeperColour, keeper, score, penaltyShot, singleShots, budget,
      players.toVector)

  val controlV20: Gen[Hsl20ControlData] =
    for {
      v19 <- controlV19
      team0 <- teamV20
      team1 <- teamV20
    } yield Hsl20ControlData(
      v19.packetNumber,
      v19.playersPerTeam,
      v19.competitionType,
      v19.stopped,
      v19.gamePhase,
      v19.gameState,
      v19.setPlay,
      v19.firstHalf,
      v19.kickingTeam,
      v19.secsRemaining,
      v19.secondaryTime,
      team0,
      team1
    )

  val hlPlayer: Gen[HlPlayerInfo] = Gen.frequency(
    2 -> Gen.const(HlPlayerInfo.Unpenalised),
    3 -> (for {
      p <- codes(HlPenalty); s <- u8; w <- u8; y <- u8; r <- u8; k <- Gen.oneOf(true, false)
    } yield HlPlayerInfo(p, s, w, y, r, k))
  )

  private def rawBytes(n: Int): Gen[ArraySeq[Byte]] = Gen.listOfN(n, Arbitrary.arbitrary[Byte]).map(ArraySeq.from(_))

  val teamV12: Gen[HlTeamInfo] = for {
    number <- u8
    colour <- codes(FieldColour)
    score <- u8
    penaltyShot <- u8
    singleShots <- u16
    sequence <- u8
    message <- rawBytes(HlPlayerInfo.CoachMessageBytes)
    coach <- hlPlayer
    players <- Gen.listOfN(HlPlayerInfo.Slots, hlPlayer)
  } yield HlTeamInfo(number, colour, score, penaltyShot, singleShots, sequence, message, coach, players.toVector)

  val controlV12: Gen[HlControlData] =
    for {
      packetNumber <- u8
      playersPerTeam <- u8
      gameType <- codes(HlGameType)
      state <- gameState
      firstHalf <- Gen.oneOf(true, false)
      kickOff <- teamOrNone
      secondary <- codes(HlSecondaryState)
      info <- rawBytes(4)
      dropInTeam <- u8
      dropInTime <- u16
      secs <- i16
      secondaryTime <- i16
      team0 <- teamV12
      team1 <- teamV12
    } yield HlControlData(packetNumber, playersPerTeam, gameType, state, firstHalf, kickOff, secondary, info,
      dropInTeam,
      dropInTime, secs.toLong, secondaryTime, team0, team1)

  val control: Gen[GameControlData] = Gen.oneOf(controlV20, controlV19, controlV12, controlV8, controlV7)

  /** Any float but NaN, the special values included. */
  val float: Gen[Float] = Gen.frequency(
    5 -> Gen.choose(-10000f, 10000f),
    1 -> Gen.oneOf(-1f, 0f, -0f, Float.MaxValue, Float.MinValue, Float.PositiveInfinity, Float.NegativeInfinity)
  )

  val returnStatus: Gen[ReturnStatus] = for {
    player <- u8
    team <- u8
    fallen <- Gen.oneOf(true, false)
    x <- float
    y <- float
    theta <- float
    age <- float
    bx <- float
    by <- float
  } yield ReturnStatus(player, team, fallen, (x, y, theta), age, (bx, by))

  val returnData: Gen[ReturnData] = for {
    team <- u8
    player <- u8
    message <- returnMessage
  } yield ReturnData(team, player, message)

  /** Byte arrays of any length up to `max`, of random content. */
  def bytes(max: Int): Gen[Array[Byte]] =
    Gen.choose(0, max).flatMap(n => Gen.containerOfN[Array, Byte](n, Arbitrary.arbitrary[Byte]))
}
