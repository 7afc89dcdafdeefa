package naogateway.testkit

import scala.collection.immutable.ArraySeq

import naogateway.wire.gamecontroller._

/** Valid GameController packets for tests. */
object GameControllerCodecSupport {

  private def team(number: Int, colour: TeamColour) = TeamInfo(
    teamNumber = number,
    teamColour = colour,
    score = 0,
    goalColour = None,
    penaltyShot = Some(0),
    singleShots = Some(0),
    coachMessage = Some(ArraySeq.fill(TeamInfo.CoachMessageBytes)(0.toByte)),
    coach = Some(PlayerInfo.Unpenalised),
    players = Vector.fill(TeamInfo.PlayerSlots)(PlayerInfo.Unpenalised)
  )

  /** A version-8 packet of a running game between `teamNumber` and team 99. */
  def playing(teamNumber: Int): ControlData2014 = ControlData2014(
    version = GameControlVersion.V8,
    packetNumber = Some(1),
    playersPerTeam = 6,
    gameState = GameState.Playing,
    firstHalf = true,
    kickOffTeam = KickOffTeam.Blue,
    secondaryGameState = SecondaryGameState.Normal,
    dropInTeam = TeamColour.Blue,
    dropInTime = -1,
    secsRemaining = 600,
    secondaryTime = Some(0),
    team0 = team(teamNumber, TeamColour.Blue),
    team1 = team(99, TeamColour.Red)
  )
}
