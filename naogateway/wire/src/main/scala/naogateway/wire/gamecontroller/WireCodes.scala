package naogateway.wire.gamecontroller

/** A value one wire code of the GameController's packets takes: the code is all the wire knows of it. */
trait WireCode extends Product with Serializable {

  /** The value on the wire. */
  def code: Int
}

/** A player's penalty code in any version: 0 is no penalty in every one. */
trait PenaltyCode extends WireCode {

  /** Whether the player is off the game for any reason. */
  def isPenalised: Boolean = code != 0
}

/** The closed set of values one wire code takes, in every version, with the value that keeps a code no known value has
  * (so decoding loses nothing and encoding gives the same byte back). Each code's table is its `known` values; a
  * value's code is its own (`isCode`: every value of such a set is a [[WireCode]]).
  */
abstract class WireCodes[A](implicit isCode: A <:< WireCode) {

  /** The known values, in code order. */
  def known: Seq[A]

  /** The value standing for `code` when no known value has it. */
  protected def unknown(code: Int): A

  /** The value with this wire code, or the unknown value carrying it. */
  def fromCode(code: Int): A = known.find(isCode(_).code == code).getOrElse(unknown(code))
}

/** A colour of the 10 the GameController of versions 12 and 19 knows (`TEAM_BLUE` … `TEAM_GRAY`). */
sealed abstract class FieldColour(val code: Int) extends WireCode

/** Colour codes of versions 12 and 19 (versions 7 and 8 know only blue and red: [[TeamColour]]). */
object FieldColour extends WireCodes[FieldColour] {

  /** Blue or cyan. */
  case object Blue extends FieldColour(0)

  /** Red, magenta or pink. */
  case object Red extends FieldColour(1)

  /** Yellow. */
  case object Yellow extends FieldColour(2)

  /** Black or dark grey. */
  case object Black extends FieldColour(3)

  /** White. */
  case object White extends FieldColour(4)

  /** Green. */
  case object Green extends FieldColour(5)

  /** Orange. */
  case object Orange extends FieldColour(6)

  /** Purple or violet. */
  case object Purple extends FieldColour(7)

  /** Brown. */
  case object Brown extends FieldColour(8)

  /** Lighter grey. */
  case object Gray extends FieldColour(9)

  /** A code no known colour has. */
  final case class Unknown(override val code: Int) extends FieldColour(code)

  val known: Seq[FieldColour] = Seq(Blue, Red, Yellow, Black, White, Green, Orange, Purple, Brown, Gray)
  protected def unknown(code: Int): FieldColour = Unknown(code)
}

/** The phase of a version-19 or -20 game (`gamePhase`). */
sealed abstract class GamePhase(val code: Int) extends WireCode

/** Game phases of versions 19 and 20. */
object GamePhase extends WireCodes[GamePhase] {

  /** A regular half. */
  case object Normal extends GamePhase(0)

  /** The penalty shoot-out: team messages are not counted. */
  case object PenaltyShootOut extends GamePhase(1)

  /** Extra time after a drawn game. */
  case object ExtraTime extends GamePhase(2)

  /** A time-out (the state reads INITIAL meanwhile). */
  case object Timeout extends GamePhase(3)

  /** A code no known phase has. */
  final case class Unknown(override val code: Int) extends GamePhase(code)

  val known: Seq[GamePhase] = Seq(Normal, PenaltyShootOut, ExtraTime, Timeout)
  protected def unknown(code: Int): GamePhase = Unknown(code)
}

/** The set play under way in a version-19 or -20 game (`setPlay`). */
sealed abstract class SetPlay(val code: Int) extends WireCode

/** Set plays of versions 19 and 20. */
object SetPlay extends WireCodes[SetPlay] {

  /** No set play (a kick-off also reads so). */
  case object NoSetPlay extends SetPlay(0)

  /** A direct free kick. */
  case object DirectFreeKick extends SetPlay(1)

  /** An indirect free kick. */
  case object IndirectFreeKick extends SetPlay(2)

  /** A penalty kick. */
  case object PenaltyKick extends SetPlay(3)

  /** A throw-in. */
  case object ThrowIn extends SetPlay(4)

  /** A goal kick. */
  case object GoalKick extends SetPlay(5)

  /** A corner kick. */
  case object CornerKick extends SetPlay(6)

  /** A code no known set play has. */
  final case class Unknown(override val code: Int) extends SetPlay(code)

  val known: Seq[SetPlay] = Seq(NoSetPlay, DirectFreeKick, IndirectFreeKick, PenaltyKick, ThrowIn, GoalKick, CornerKick)
  protected def unknown(code: Int): SetPlay = Unknown(code)
}

/** The division a version-19 or -20 game is played in (`competitionType`). */
sealed abstract class CompetitionType(val code: Int) extends WireCode

/** Competition types of versions 19 and 20. */
object CompetitionType extends WireCodes[CompetitionType] {

  /** The small division. */
  case object Small extends CompetitionType(0)

  /** The middle division. */
  case object Middle extends CompetitionType(1)

  /** The large division. */
  case object Large extends CompetitionType(2)

  /** A code no known type has. */
  final case class Unknown(override val code: Int) extends CompetitionType(code)

  val known: Seq[CompetitionType] = Seq(Small, Middle, Large)
  protected def unknown(code: Int): CompetitionType = Unknown(code)
}

/** The kind of a version-12 game (`gameType`). */
sealed abstract class HlGameType(val code: Int) extends WireCode

/** Game types of version 12. */
object HlGameType extends WireCodes[HlGameType] {

  /** Kid size. */
  case object KidSize extends HlGameType(0)

  /** Adult size. */
  case object AdultSize extends HlGameType(1)

  /** Drop-in. */
  case object DropIn extends HlGameType(2)

  /** A code no known type has. */
  final case class Unknown(override val code: Int) extends HlGameType(code)

  val known: Seq[HlGameType] = Seq(KidSize, AdultSize, DropIn)
  protected def unknown(code: Int): HlGameType = Unknown(code)
}

/** Extra state of a version-12 game (`secondaryState`): the phase, or the set play under way. */
sealed abstract class HlSecondaryState(val code: Int) extends WireCode

/** Secondary states of version 12. */
object HlSecondaryState extends WireCodes[HlSecondaryState] {

  /** Regular play. */
  case object Normal extends HlSecondaryState(0)

  /** The penalty shoot-out. */
  case object PenaltyShoot extends HlSecondaryState(1)

  /** Extra time. */
  case object Overtime extends HlSecondaryState(2)

  /** A time-out. */
  case object Timeout extends HlSecondaryState(3)

  /** A direct free kick. */
  case object DirectFreeKick extends HlSecondaryState(4)

  /** An indirect free kick. */
  case object IndirectFreeKick extends HlSecondaryState(5)

  /** A penalty kick. */
  case object PenaltyKick extends HlSecondaryState(6)

  /** A corner kick. */
  case object CornerKick extends HlSecondaryState(7)

  /** A goal kick. */
  case object GoalKick extends HlSecondaryState(8)

  /** A throw-in. */
  case object ThrowIn extends HlSecondaryState(9)

  /** A code no known state has. */
  final case class Unknown(override val code: Int) extends HlSecondaryState(code)

  val known: Seq[HlSecondaryState] = Seq(Normal, PenaltyShoot, Overtime, Timeout, DirectFreeKick, IndirectFreeKick,
    PenaltyKick, CornerKick, GoalKick, ThrowIn)
  protected def unknown(code: Int): HlSecondaryState = Unknown(code)
}
