package naogateway.wire.gamecontroller

import scala.collection.immutable.ArraySeq

import org.scalacheck.{Arbitrary, Gen}

/** Generators of valid GameController values of both versions, with unknown codes mixed in. */
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

  val controlV8: Gen[GameControlData] = for {
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
  } yield GameControlData(
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

  val controlV7: Gen[GameControlData] = for {
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
  } yield GameControlData(
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

  val control: Gen[GameControlData] = Gen.oneOf(controlV8, controlV7)

  val returnData: Gen[ReturnData] = for {
    team <- u8
    player <- u8
    message <- returnMessage
  } yield ReturnData(team, player, message)

  /** Byte arrays of any length up to `max`, of random content. */
  def bytes(max: Int): Gen[Array[Byte]] =
    Gen.choose(0, max).flatMap(n => Gen.containerOfN[Array, Byte](n, Arbitrary.arbitrary[Byte]))
}
