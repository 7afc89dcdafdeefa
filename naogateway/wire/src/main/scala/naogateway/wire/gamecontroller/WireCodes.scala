package naogateway.wire.gamecontroller

/** A value one wire code of the GameController's packets takes: the code is all the wire knows of it. */
trait WireCode extends Product with Serializable {

  /** The value on the wire. */
  def code: Int
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

/** Why a version-19 player is off the game (`penalty`). */
sealed abstract class HslPenalty(val code: Int) extends WireCode {

  /** Whether the player is off the game for any reason. */
  def isPenalised: Boolean = code != 0
}

/** Penalties of version 19. */
object HslPenalty extends WireCodes[HslPenalty] {

  /** Not penalised. */
  case object NoPenalty extends HslPenalty(0)

  /** Illegal positioning. */
  case object IllegalPositioning extends HslPenalty(1)

  /** Moved in SET. */
  case object MotionInSet extends HslPenalty(2)

  /** Local game stuck. */
  case object LocalGameStuck extends HslPenalty(3)

  /** Incapable robot. */
  case object IncapableRobot extends HslPenalty(4)

  /** Picked up. */
  case object PickUp extends HslPenalty(5)

  /** Ball holding. */
  case object BallHolding extends HslPenalty(6)

  /** Left the field. */
  case object LeavingTheField extends HslPenalty(7)

  /** Played with arms or hands. */
  case object PlayingWithArmsHands extends HslPenalty(8)

  /** Pushing. */
  case object Pushing extends HslPenalty(9)

  /** Sent off. */
  case object SentOff extends HslPenalty(10)

  /** A substitute, not on the field. */
  case object Substitute extends HslPenalty(11)

  /** A code no known penalty has. */
  final case class Unknown(override val code: Int) extends HslPenalty(code)

  val known: Seq[HslPenalty] = Seq(
    NoPenalty,
    IllegalPositioning,
    MotionInSet,
    LocalGameStuck,
    IncapableRobot,
    PickUp,
    BallHolding,
    LeavingTheField,
    PlayingWithArmsHands,
    Pushing,
    SentOff,
    Substitute
  )
  protected def unknown(code: Int): HslPenalty = Unknown(code)
}

/** Why a version-20 player is off the game (`penalty`): version 19's set renumbered, with motion in stop (3) and
  * cautioned (11) new.
  */
sealed abstract class Hsl20Penalty(val code: Int) extends WireCode {

  /** Whether the player is off the game for any reason. */
  def isPenalised: Boolean = code != 0
}

/** Penalties of version 20. */
object Hsl20Penalty extends WireCodes[Hsl20Penalty] {

  /** Not penalised. */
  case object NoPenalty extends Hsl20Penalty(0)

  /** Illegal positioning. */
  case object IllegalPositioning extends Hsl20Penalty(1)

  /** Moved in SET. */
  case object MotionInSet extends Hsl20Penalty(2)

  /** Moved while play was stopped. */
  case object MotionInStop extends Hsl20Penalty(3)

  /** Local game stuck. */
  case object LocalGameStuck extends Hsl20Penalty(4)

  /** Incapable robot. */
  case object IncapableRobot extends Hsl20Penalty(5)

  /** Picked up. */
  case object PickUp extends Hsl20Penalty(6)

  /** Ball holding. */
  case object BallHolding extends Hsl20Penalty(7)

  /** Left the field. */
  case object LeavingTheField extends Hsl20Penalty(8)

  /** Played with arms or hands. */
  case object PlayingWithArmsHands extends Hsl20Penalty(9)

  /** Pushing. */
  case object Pushing extends Hsl20Penalty(10)

  /** Cautioned (a yellow card) and off for its time. */
  case object Cautioned extends Hsl20Penalty(11)

  /** Sent off. */
  case object SentOff extends Hsl20Penalty(12)

  /** A substitute, not on the field. */
  case object Substitute extends Hsl20Penalty(13)

  /** A code no known penalty has. */
  final case class Unknown(override val code: Int) extends Hsl20Penalty(code)

  val known: Seq[Hsl20Penalty] = Seq(
    NoPenalty,
    IllegalPositioning,
    MotionInSet,
    MotionInStop,
    LocalGameStuck,
    IncapableRobot,
    PickUp,
    BallHolding,
    LeavingTheField,
    PlayingWithArmsHands,
    Pushing,
    Cautioned,
    SentOff,
    Substitute
  )
  protected def unknown(code: Int): Hsl20Penalty = Unknown(code)
}

/** Why a version-12 player is off the game (`penalty`, the Humanoid League's codes). */
sealed abstract class HlPenalty(val code: Int) extends WireCode {

  /** Whether the player is off the game for any reason. */
  def isPenalised: Boolean = code != 0
}

/** Penalties the version-12 GameController writes. */
object HlPenalty extends WireCodes[HlPenalty] {

  /** Not penalised. */
  case object NoPenalty extends HlPenalty(0)

  /** A substitute. */
  case object Substitute extends HlPenalty(14)

  /** Penalised by hand. */
  case object Manual extends HlPenalty(15)

  /** Ball manipulation. */
  case object BallManipulation extends HlPenalty(30)

  /** Physical contact (pushing). */
  case object PhysicalContact extends HlPenalty(31)

  /** An illegal attack. */
  case object IllegalAttack extends HlPenalty(32)

  /** An illegal defence. */
  case object IllegalDefense extends HlPenalty(33)

  /** Picked up, or incapable. */
  case object PickupOrIncapable extends HlPenalty(34)

  /** Service. */
  case object Service extends HlPenalty(35)

  /** A penalty the version-12 layout has no code for (the GameController writes 255). */
  case object Unspecified extends HlPenalty(255)

  /** A code no known penalty has. */
  final case class Unknown(override val code: Int) extends HlPenalty(code)

  val known: Seq[HlPenalty] = Seq(NoPenalty, Substitute, Manual, BallManipulation, PhysicalContact, IllegalAttack,
    IllegalDefense, PickupOrIncapable, Service, Unspecified)
  protected def unknown(code: Int): HlPenalty = Unknown(code)
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
