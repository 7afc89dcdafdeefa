package naogateway.wire.gamecontroller

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
  def penaltyOf(teamNumber: Int, player: Int): Option[PlayerPenalty] =
    teamByNumber(teamNumber).flatMap(_.players.lift(player - 1)).flatMap(_.playerPenalty)

  /** The team with this team number, if it plays in this game. */
  def teamByNumber(teamNumber: Int): Option[GameTeam] =
    if (team0.teamNumber == teamNumber) Some(team0)
    else if (team1.teamNumber == teamNumber) Some(team1)
    else None
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
}

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
}

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
}

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
}
