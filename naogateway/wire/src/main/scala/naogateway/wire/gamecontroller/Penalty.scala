package naogateway.wire.gamecontroller

/** Why a player is off the game (`penalty`: one byte in version 8, two in version 7). */
sealed abstract class Penalty(val code: Int) extends PenaltyCode

/** Penalties as the humanoid kid-size league numbers them. The same codes mean other fouls in the standard-platform and
  * teen-size leagues; this project's robots play kid-size, so that is the reading.
  */
object Penalty extends WireCodes[Penalty] {

  /** Not penalised. */
  case object NoPenalty extends Penalty(0)

  /** Touched the ball with arms or hands. */
  case object BallManipulation extends Penalty(1)

  /** Illegal physical contact with an opponent. */
  case object PhysicalContact extends Penalty(2)

  /** An illegal attack under the kid-size rules. */
  case object IllegalAttack extends Penalty(3)

  /** An illegal defence under the kid-size rules. */
  case object IllegalDefense extends Penalty(4)

  /** The team asked to pick the robot up. */
  case object RequestForPickup extends Penalty(5)

  /** The team asked to service the robot. */
  case object RequestForService extends Penalty(6)

  /** A pick-up was turned into a service. */
  case object RequestForPickupToService extends Penalty(7)

  /** The player is a substitute, not on the field. */
  case object Substitute extends Penalty(14)

  /** Penalised by hand on the GameController (or by the robot's own return packet). */
  case object Manual extends Penalty(15)

  /** A value outside the known set; decoding produces it only for codes no known penalty has. */
  final case class Unknown(override val code: Int) extends Penalty(code)

  /** The known penalties, in code order. */
  val known: Seq[Penalty] = Seq(
    NoPenalty,
    BallManipulation,
    PhysicalContact,
    IllegalAttack,
    IllegalDefense,
    RequestForPickup,
    RequestForService,
    RequestForPickupToService,
    Substitute,
    Manual
  )
  protected def unknown(code: Int): Penalty = Unknown(code)
}

/** Why a version-19 player is off the game (`penalty`). */
sealed abstract class HslPenalty(val code: Int) extends PenaltyCode

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
sealed abstract class Hsl20Penalty(val code: Int) extends PenaltyCode

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
sealed abstract class HlPenalty(val code: Int) extends PenaltyCode

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
