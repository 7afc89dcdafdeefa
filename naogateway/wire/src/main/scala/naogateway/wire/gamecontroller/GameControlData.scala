package naogateway.wire.gamecontroller

import scala.collection.immutable.ArraySeq

/** A layout of the `RGme` control packet, with its exact size on the wire. */
sealed abstract class GameControlVersion(val number: Int, val packetBytes: Int) extends Product with Serializable

/** The two layouts the GameController broadcasts to the humanoid leagues each round (docs/protocol.md §3 and §10). */
object GameControlVersion {

  /** The current layout: u8 version, 158 bytes. */
  case object V8 extends GameControlVersion(8, 158)

  /** The older layout still broadcast for the humanoid leagues: u32 version, 116 bytes. */
  case object V7 extends GameControlVersion(7, 116)
}

/**
 * One player's entry (`RobotInfo`): one byte each in version 8, two bytes each in version 7.
 *
 * @param secsTillUnpenalised the GameController's estimate; 0 when not penalised
 */
final case class PlayerInfo(penalty: Penalty, secsTillUnpenalised: Int) {

  /** Whether the player is off the game for any reason. */
  def isPenalised: Boolean = penalty != Penalty.NoPenalty
}

/** Constructors of player entries. */
object PlayerInfo {

  /** A player in the game. */
  val Unpenalised: PlayerInfo = PlayerInfo(Penalty.NoPenalty, 0)
}

/**
 * One team's entry (`TeamInfo`). Fields one version lacks are `None` in packets of that version, and
 * must be `None` to encode in it; fields it has must be present.
 *
 * @param goalColour   version 7 only
 * @param penaltyShot  version 8 only: penalty shot counter
 * @param singleShots  version 8 only: u16 whose bits are the successful penalty shots
 * @param coachMessage version 8 only: the 40 raw bytes of the coach message, usually zero-padded text
 * @param coach        version 8 only: the coach's penalty state
 * @param players      always all 11 slots of the wire, of which `playersPerTeam` are in use
 */
final case class TeamInfo(
    teamNumber: Int,
    teamColour: TeamColour,
    score: Int,
    goalColour: Option[GoalColour],
    penaltyShot: Option[Int],
    singleShots: Option[Int],
    coachMessage: Option[ArraySeq[Byte]],
    coach: Option[PlayerInfo],
    players: Vector[PlayerInfo]
)

/** Sizes shared by both layouts. */
object TeamInfo {

  /** Player slots per team on the wire (`MAX_NUM_PLAYERS`), whatever `playersPerTeam` says. */
  val PlayerSlots: Int = 11

  /** Bytes of the version-8 coach message. */
  val CoachMessageBytes: Int = 40
}

/**
 * The content of one `RGme` control packet of either version, every wire field kept: decoding an
 * accepted packet and encoding the result gives back the same bytes. Fields one version lacks are
 * `None` in packets of that version.
 *
 * @param packetNumber  version 8 only: counts up with each packet, wrapping at 256
 * @param firstHalf     the wire's `firstHalf` byte, 1 or 0 (anything else is refused)
 * @param dropInTeam    the colour of the team that caused the last drop-in
 * @param dropInTime    seconds since the last drop-in, −1 before the first
 * @param secsRemaining seconds left in the half: i16 in version 8, u32 in version 7
 * @param secondaryTime version 8 only: seconds of the secondary clock (ready phase, time-out, …)
 * @param team0         the wire's `teams[0]`
 * @param team1         the wire's `teams[1]`
 */
final case class GameControlData(
    version: GameControlVersion,
    packetNumber: Option[Int],
    playersPerTeam: Int,
    gameState: GameState,
    firstHalf: Boolean,
    kickOffTeam: KickOffTeam,
    secondaryGameState: SecondaryGameState,
    dropInTeam: TeamColour,
    dropInTime: Int,
    secsRemaining: Long,
    secondaryTime: Option[Int],
    team0: TeamInfo,
    team1: TeamInfo
) {

  /** The team with this team number, if it plays in this game. */
  def teamByNumber(teamNumber: Int): Option[TeamInfo] =
    if (team0.teamNumber == teamNumber) Some(team0)
    else if (team1.teamNumber == teamNumber) Some(team1)
    else None
}
