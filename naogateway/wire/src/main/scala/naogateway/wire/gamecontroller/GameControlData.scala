package naogateway.wire.gamecontroller

import scala.collection.immutable.ArraySeq

/** A layout of the `RGme` control packet, with its exact size on the wire and the width of its version field
  * (docs/protocol.md §10).
  */
sealed abstract class GameControlVersion(val number: Int, val packetBytes: Int, val versionBytes: Int)
    extends Product with Serializable

/** The layouts a team may meet: the Humanoid Soccer League's of RoboCup 2026 (20) and of early 2026 (19), the Humanoid
  * League's until 2025 (12), 2014's (8, 7).
  */
object GameControlVersion {

  /** The Humanoid Soccer League's GameController 7 (RoboCup 2026): u8 version, 158 bytes. */
  case object V20 extends GameControlVersion(20, 158, 1)

  /** The Humanoid Soccer League's GameController 6 (early 2026, German Open 2026): u8 version, 198 bytes. */
  case object V19 extends GameControlVersion(19, 198, 1)

  /** The Humanoid League's GameController until 2025: u16 version, 688 bytes. */
  case object V12 extends GameControlVersion(12, 688, 2)

  /** The 2014 layout: u8 version, 158 bytes. */
  case object V8 extends GameControlVersion(8, 158, 1)

  /** The older layout the 2014 GameController also broadcast for the humanoid leagues: u32 version, 116 bytes. */
  case object V7 extends GameControlVersion(7, 116, 4)

  /** Every version the codec reads, newest first. */
  val all: Seq[GameControlVersion] = Seq(V20, V19, V12, V8, V7)
}

/** A player the GameController has taken off the game, in any version: its penalty (the version's own code) by name,
  * and the seconds left until it may play again (0: not timed, as for a substitute or a robot sent off).
  */
final case class PlayerPenalty(penalty: WireCode, secsTillUnpenalised: Int) {

  /** The penalty in words, as the GameController's display names it: "pushing", "motion in stop", "unknown(42)". */
  def name: String = penalty.toString.replaceAll("([a-z])([A-Z])", "$1 $2").toLowerCase

  /** One phrase for screens: "pushing, 25 s left". */
  def describe: String = if (secsTillUnpenalised > 0) s"$name, $secsTillUnpenalised s left" else name
}

/** Picking one player's entry out of a team list. */
private[gamecontroller] object PenaltyLookup {

  /** Player `player` (from 1) of the team numbered `teamNumber` among `teams`, as `penalty` reads its entry. */
  def find[T <: GameTeam, P](teams: Seq[T], teamNumber: Int, player: Int)(players: T => Vector[P])(
      penalty: P => Option[PlayerPenalty]): Option[PlayerPenalty] =
    teams.find(_.teamNumber == teamNumber).flatMap(t => players(t).lift(player - 1)).flatMap(penalty)
}

/** What every team entry of every version says: who the team is and its score. */
trait GameTeam {

  /** The team's unique number. */
  def teamNumber: Int

  /** The team's score. */
  def score: Int
}

/** The content of one `RGme` control packet of any version: what all versions say, as members; the rest in the
  * version's own type ([[ControlData2014]], [[HlControlData]], [[HslControlData]]), so no field is invented where a
  * version lacks it.
  */
sealed trait GameControlData extends Product with Serializable {

  /** The layout the packet came in. */
  def version: GameControlVersion

  /** The packet number, counting up with each packet and wrapping at 256; version 7 has none. */
  def packetNumberOnWire: Option[Int]

  /** Players per team in this game. */
  def playersPerTeam: Int

  /** The main state: the competition gate reads this. */
  def gameState: GameState

  /** Whether the game is in its first half (of regular or extra time). */
  def firstHalf: Boolean

  /** Seconds left in the half (negative: over time). */
  def secsRemaining: Long

  /** Seconds of the secondary clock (ready phase, set play, time-out …); version 7 has none. */
  def secondaryClock: Option[Int]

  /** The wire's `teams[0]`. */
  def team0: GameTeam

  /** The wire's `teams[1]`. */
  def team1: GameTeam

  /** Whether a penalty shoot-out is under way (team messages are not counted then). */
  def penaltyShootOut: Boolean

  /** The penalty of player `player` (counted from 1) of team `teamNumber`, when the packet has that player and the
    * GameController has taken it off the game (a substitute included); `None` otherwise.
    */
  def penaltyOf(teamNumber: Int, player: Int): Option[PlayerPenalty]

  /** The team with this team number, if it plays in this game. */
  def teamByNumber(teamNumber: Int): Option[GameTeam] =
    if (team0.teamNumber == teamNumber) Some(team0)
    else if (team1.teamNumber == teamNumber) Some(team1)
    else None
}

/** One player's entry (`RobotInfo`): one byte each in version 8, two bytes each in version 7.
  *
  * @param secsTillUnpenalised
  *   the GameController's estimate; 0 when not penalised
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

/** One team's entry (`TeamInfo`). Fields one version lacks are `None` in packets of that version, and must be `None` to
  * encode in it; fields it has must be present.
  *
  * @param goalColour
  *   version 7 only
  * @param penaltyShot
  *   version 8 only: penalty shot counter
  * @param singleShots
  *   version 8 only: u16 whose bits are the successful penalty shots
  * @param coachMessage
  *   version 8 only: the 40 raw bytes of the coach message, usually zero-padded text
  * @param coach
  *   version 8 only: the coach's penalty state
  * @param players
  *   always all 11 slots of the wire, of which `playersPerTeam` are in use
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
) extends GameTeam

/** Sizes shared by both layouts. */
object TeamInfo {

  /** Player slots per team on the wire (`MAX_NUM_PLAYERS`), whatever `playersPerTeam` says. */
  val PlayerSlots: Int = 11

  /** Bytes of the version-8 coach message. */
  val CoachMessageBytes: Int = 40
}

/** The content of one `RGme` control packet of version 8 or 7 (2014), every wire field kept: decoding an accepted
  * packet and encoding the result gives back the same bytes. Fields one version lacks are `None` in packets of that
  * version.
  *
  * @param packetNumber
  *   version 8 only: counts up with each packet, wrapping at 256
  * @param firstHalf
  *   the wire's `firstHalf` byte, 1 or 0 (anything else is refused)
  * @param dropInTeam
  *   the colour of the team that caused the last drop-in
  * @param dropInTime
  *   seconds since the last drop-in, −1 before the first
  * @param secsRemaining
  *   seconds left in the half: i16 in version 8, u32 in version 7
  * @param secondaryTime
  *   version 8 only: seconds of the secondary clock (ready phase, time-out, …)
  * @param team0
  *   the wire's `teams[0]`
  * @param team1
  *   the wire's `teams[1]`
  */
final case class ControlData2014(
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
) extends GameControlData {

  def packetNumberOnWire: Option[Int] = packetNumber
  def secondaryClock: Option[Int] = secondaryTime
  def penaltyShootOut: Boolean = secondaryGameState == SecondaryGameState.PenaltyShoot
  def penaltyOf(teamNumber: Int, player: Int): Option[PlayerPenalty] =
    PenaltyLookup.find(Seq(team0, team1), teamNumber, player)(_.players)(p =>
      Option.when(p.isPenalised)(PlayerPenalty(p.penalty, p.secsTillUnpenalised)))
}

/** One player's entry of version 19 (`RobotInfo`, 4 bytes).
  *
  * @param secsTillUnpenalised
  *   the GameController's estimate; 0 when not penalised
  * @param cautions
  *   yellow cards
  */
final case class HslPlayerInfo(penalty: HslPenalty, secsTillUnpenalised: Int, warnings: Int, cautions: Int)

/** Constructors of version-19 player entries. */
object HslPlayerInfo {

  /** A player in the game, with no warning or caution. */
  val Unpenalised: HslPlayerInfo = HslPlayerInfo(HslPenalty.NoPenalty, 0, 0, 0)

  /** Player slots per team on the wire (`MAX_NUM_PLAYERS`). */
  val Slots: Int = 20
}

/** One team's entry of version 19 (`TeamInfo`, 90 bytes).
  *
  * @param goalkeeper
  *   the goalkeeper's player number; 0 for none
  * @param singleShots
  *   bits are the successful penalty shots
  * @param messageBudget
  *   team messages the team may still send in this game (docs/protocol.md §10.5)
  * @param players
  *   always all 20 slots of the wire
  */
final case class HslTeamInfo(
    teamNumber: Int,
    fieldPlayerColour: FieldColour,
    goalkeeperColour: FieldColour,
    goalkeeper: Int,
    score: Int,
    penaltyShot: Int,
    singleShots: Int,
    messageBudget: Int,
    players: Vector[HslPlayerInfo]
) extends HslTeam

/** What the Humanoid Soccer League's packets of versions 18, 19 and 20 say in their shared first 18 bytes
  * (docs/protocol.md §10.2), as members: the gateway reads both versions alike through it, and a later version by its
  * header alone ([[SharedHeader]]).
  */
sealed trait HslHeaderFields {

  /** The packet number, counting up with each packet and wrapping at 256. */
  def packetNumber: Int

  /** Players per team in this game. */
  def playersPerTeam: Int

  /** The division the game is played in. */
  def competitionType: CompetitionType

  /** Play is stopped (a foul, a set play being prepared) though the state may read PLAYING. */
  def stopped: Boolean

  /** The phase: normal, penalty shoot-out, extra time, time-out. */
  def gamePhase: GamePhase

  /** The main state. */
  def gameState: GameState

  /** The set play under way. */
  def setPlay: SetPlay

  /** Whether the game is in its first half. */
  def firstHalf: Boolean

  /** The team number of the team taking the next kick-off or set play; `None` on the wire's 255. */
  def kickingTeam: Option[Int]

  /** Seconds left in the half (negative: over time). */
  def secsRemaining: Long

  /** Seconds of the secondary clock. */
  def secondaryTime: Int
}

/** The shared first 18 bytes of an `RGme` packet of a Humanoid Soccer League version this codec does not know (18, or
  * above 20), read by [[GameControllerCodec.decodeSharedHeader]]: enough for the competition gate, nothing about the
  * teams (docs/protocol.md §10.8).
  *
  * @param versionNumber
  *   the packet's version byte
  * @param packetBytes
  *   the packet's size
  */
final case class SharedHeader(
    versionNumber: Int,
    packetBytes: Int,
    packetNumber: Int,
    playersPerTeam: Int,
    competitionType: CompetitionType,
    stopped: Boolean,
    gamePhase: GamePhase,
    gameState: GameState,
    setPlay: SetPlay,
    firstHalf: Boolean,
    kickingTeam: Option[Int],
    secsRemaining: Long,
    secondaryTime: Int
) extends HslHeaderFields

/** A team entry of the Humanoid Soccer League's versions 19 and 20: what both say of a team beyond its number. */
sealed trait HslTeam extends GameTeam {

  /** Team messages the team may still send in this game (docs/protocol.md §10.5). */
  def messageBudget: Int
}

/** A control packet of the Humanoid Soccer League's versions 19 or 20, which the gateway treats alike: the header's
  * fields and each team's message budget. The same layouts come with header `RGme` (broadcast) or `RGTD` (the true
  * state for a monitor).
  */
sealed trait HslGameData extends GameControlData with HslHeaderFields {
  def team0: HslTeam
  def team1: HslTeam
  def packetNumberOnWire: Option[Int] = Some(packetNumber)
  def secondaryClock: Option[Int] = Some(secondaryTime)
  def penaltyShootOut: Boolean = gamePhase == GamePhase.PenaltyShootOut
}

/** The content of one version-19 control packet (198 bytes, the Humanoid Soccer League's GameController 6, early 2026),
  * every wire field kept.
  */
final case class HslControlData(
    packetNumber: Int,
    playersPerTeam: Int,
    competitionType: CompetitionType,
    stopped: Boolean,
    gamePhase: GamePhase,
    gameState: GameState,
    setPlay: SetPlay,
    firstHalf: Boolean,
    kickingTeam: Option[Int],
    secsRemaining: Long,
    secondaryTime: Int,
    team0: HslTeamInfo,
    team1: HslTeamInfo
) extends HslGameData {
  def version: GameControlVersion = GameControlVersion.V19
  def penaltyOf(teamNumber: Int, player: Int): Option[PlayerPenalty] =
    PenaltyLookup.find(Seq(team0, team1), teamNumber, player)(_.players)(p =>
      Option.when(p.penalty.isPenalised)(PlayerPenalty(p.penalty, p.secsTillUnpenalised)))
}

/** One player's entry of version 20 (`RobotInfo`, 3 bytes: version 19's `warnings` is gone).
  *
  * @param secsTillUnpenalised
  *   the GameController's estimate; 0 when not penalised
  * @param cautions
  *   yellow cards
  */
final case class Hsl20PlayerInfo(penalty: Hsl20Penalty, secsTillUnpenalised: Int, cautions: Int)

/** Constructors of version-20 player entries. */
object Hsl20PlayerInfo {

  /** A player in the game, with no caution. */
  val Unpenalised: Hsl20PlayerInfo = Hsl20PlayerInfo(Hsl20Penalty.NoPenalty, 0, 0)

  /** Player slots per team on the wire (`MAX_NUM_PLAYERS`). */
  val Slots: Int = 20
}

/** One team's entry of version 20 (`TeamInfo`, 70 bytes), the fields of version 19's in the same order.
  *
  * @param goalkeeper
  *   the goalkeeper's player number; 0 for none
  * @param singleShots
  *   bits are the successful penalty shots
  * @param players
  *   always all 20 slots of the wire
  */
final case class Hsl20TeamInfo(
    teamNumber: Int,
    fieldPlayerColour: FieldColour,
    goalkeeperColour: FieldColour,
    goalkeeper: Int,
    score: Int,
    penaltyShot: Int,
    singleShots: Int,
    messageBudget: Int,
    players: Vector[Hsl20PlayerInfo]
) extends HslTeam

/** The content of one version-20 control packet (158 bytes, the Humanoid Soccer League's GameController 7, RoboCup
  * 2026), every wire field kept. Its header is version 19's; its teams and penalties are its own.
  */
final case class Hsl20ControlData(
    packetNumber: Int,
    playersPerTeam: Int,
    competitionType: CompetitionType,
    stopped: Boolean,
    gamePhase: GamePhase,
    gameState: GameState,
    setPlay: SetPlay,
    firstHalf: Boolean,
    kickingTeam: Option[Int],
    secsRemaining: Long,
    secondaryTime: Int,
    team0: Hsl20TeamInfo,
    team1: Hsl20TeamInfo
) extends HslGameData {
  def version: GameControlVersion = GameControlVersion.V20
  def penaltyOf(teamNumber: Int, player: Int): Option[PlayerPenalty] =
    PenaltyLookup.find(Seq(team0, team1), teamNumber, player)(_.players)(p =>
      Option.when(p.penalty.isPenalised)(PlayerPenalty(p.penalty, p.secsTillUnpenalised)))
}

/** One player's entry of version 12 (`HlRobotInfo`, 6 bytes).
  *
  * @param goalkeeper
  *   whether the player is the goalkeeper (the wire's flag, 0 or 1)
  */
final case class HlPlayerInfo(
    penalty: HlPenalty,
    secsTillUnpenalised: Int,
    warnings: Int,
    yellowCards: Int,
    redCards: Int,
    goalkeeper: Boolean
)

/** Constructors of version-12 player entries. */
object HlPlayerInfo {

  /** A player in the game, with no card. */
  val Unpenalised: HlPlayerInfo = HlPlayerInfo(HlPenalty.NoPenalty, 0, 0, 0, 0, goalkeeper = false)

  /** Player slots per team on the wire (`MAX_NUM_PLAYERS` of that header). */
  val Slots: Int = 11

  /** Bytes of the coach message. */
  val CoachMessageBytes: Int = 253
}

/** One team's entry of version 12 (`HlTeamInfo`, 332 bytes).
  *
  * @param coachMessage
  *   the 253 raw bytes of the coach's message
  * @param players
  *   always all 11 slots of the wire
  */
final case class HlTeamInfo(
    teamNumber: Int,
    fieldPlayerColour: FieldColour,
    score: Int,
    penaltyShot: Int,
    singleShots: Int,
    coachSequence: Int,
    coachMessage: scala.collection.immutable.ArraySeq[Byte],
    coach: HlPlayerInfo,
    players: Vector[HlPlayerInfo]
) extends GameTeam

/** The content of one version-12 control packet (688 bytes, the Humanoid League's GameController until 2025), every
  * wire field kept.
  *
  * @param kickOffTeam
  *   the team number of the team kicking off next; `None` on the wire's 255 (dropped ball)
  * @param secondaryStateInfo
  *   the 4 raw bytes of `secondaryStateInfo` (the GameController writes the set play's team number and its phase in the
  *   first two)
  * @param dropInTime
  *   the wire's u16; 65535 before the first drop-in
  * @param secsRemaining
  *   read as the i16 the GameController writes (the header calls it u16)
  */
final case class HlControlData(
    packetNumber: Int,
    playersPerTeam: Int,
    gameType: HlGameType,
    gameState: GameState,
    firstHalf: Boolean,
    kickOffTeam: Option[Int],
    secondaryState: HlSecondaryState,
    secondaryStateInfo: scala.collection.immutable.ArraySeq[Byte],
    dropInTeam: Int,
    dropInTime: Int,
    secsRemaining: Long,
    secondaryTime: Int,
    team0: HlTeamInfo,
    team1: HlTeamInfo
) extends GameControlData {
  def version: GameControlVersion = GameControlVersion.V12
  def packetNumberOnWire: Option[Int] = Some(packetNumber)
  def secondaryClock: Option[Int] = Some(secondaryTime)
  def penaltyShootOut: Boolean = secondaryState == HlSecondaryState.PenaltyShoot
  def penaltyOf(teamNumber: Int, player: Int): Option[PlayerPenalty] =
    PenaltyLookup.find(Seq(team0, team1), teamNumber, player)(_.players)(p =>
      Option.when(p.penalty.isPenalised)(PlayerPenalty(p.penalty, p.secsTillUnpenalised)))
}
