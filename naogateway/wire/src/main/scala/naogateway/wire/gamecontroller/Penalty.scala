package naogateway.wire.gamecontroller

/** Why a player is off the game (`penalty`: one byte in version 8, two in version 7). */
sealed abstract class Penalty(val code: Int) extends WireCode

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
