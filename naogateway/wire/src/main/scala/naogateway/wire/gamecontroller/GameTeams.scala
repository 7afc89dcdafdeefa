package naogateway.wire.gamecontroller

import scala.collection.immutable.ArraySeq

/** A player the GameController has taken off the game, in any version: its penalty (the version's own code) by name,
  * and the seconds left until it may play again (0: not timed, as for a substitute or a robot sent off).
  */
final case class PlayerPenalty(penalty: WireCode, secsTillUnpenalised: Int) {

  /** The penalty in words, as the GameController's display names it: "pushing", "motion in stop", "unknown(42)". */
  def name: String = penalty.toString.replaceAll("([a-z])([A-Z])", "$1 $2").toLowerCase

  /** One phrase for screens: "pushing, 25 s left". */
  def describe: String = if (secsTillUnpenalised > 0) s"$name, $secsTillUnpenalised s left" else name
}

/** What every team entry of every version says: who the team is and its score. */
trait GameTeam {

  /** The team's unique number. */
  def teamNumber: Int

  /** The team's score. */
  def score: Int

  /** The players' entries, every slot of the wire. */
  def players: Vector[PlayerEntry]
}

/** What every player entry of every version says: its penalty (the version's own code) and how long it lasts. */
trait PlayerEntry {

  /** The player's penalty code. */
  def penalty: PenaltyCode

  /** The GameController's estimate of the seconds left; 0 when not penalised. */
  def secsTillUnpenalised: Int

  /** Whether the player is off the game for any reason. */
  def isPenalised: Boolean = penalty.isPenalised

  /** The penalty as every version tells it, when the player is off the game. */
  def playerPenalty: Option[PlayerPenalty] = Option.when(isPenalised)(PlayerPenalty(penalty, secsTillUnpenalised))
}

/** One player's entry (`RobotInfo`): one byte each in version 8, two bytes each in version 7.
  *
  * @param secsTillUnpenalised
  *   the GameController's estimate; 0 when not penalised
  */
final case class PlayerInfo(penalty: Penalty, secsTillUnpenalised: Int) extends PlayerEntry

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

/** One player's entry of version 19 (`RobotInfo`, 4 bytes).
  *
  * @param secsTillUnpenalised
  *   the GameController's estimate; 0 when not penalised
  * @param cautions
  *   yellow cards
  */
final case class HslPlayerInfo(penalty: HslPenalty, secsTillUnpenalised: Int, warnings: Int, cautions: Int)
    extends PlayerEntry

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

/** A team entry of the Humanoid Soccer League's versions 19 and 20: what both say of a team beyond its number. */
sealed trait HslTeam extends GameTeam {

  /** Team messages the team may still send in this game (docs/protocol.md §10.5). */
  def messageBudget: Int
}

/** One player's entry of version 20 (`RobotInfo`, 3 bytes: version 19's `warnings` is gone).
  *
  * @param secsTillUnpenalised
  *   the GameController's estimate; 0 when not penalised
  * @param cautions
  *   yellow cards
  */
final case class Hsl20PlayerInfo(penalty: Hsl20Penalty, secsTillUnpenalised: Int, cautions: Int) extends PlayerEntry

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
) extends PlayerEntry

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
    coachMessage: ArraySeq[Byte],
    coach: HlPlayerInfo,
    players: Vector[HlPlayerInfo]
) extends GameTeam
