package naogateway.wire.gamecontroller

/** Why a player is off the game (`penalty`: one byte in version 8, two in version 7). */
sealed trait Penalty extends Product with Serializable {

  /** The value on the wire. */
  def code: Int
}

/** Penalties as the humanoid kid-size league numbers them. The same codes mean other fouls in the standard-platform and
  * teen-size leagues; this project's robots play kid-size, so that is the reading.
  */
object Penalty {

  /** Not penalised. */
  case object NoPenalty extends Penalty { val code: Int = 0 }

  /** Touched the ball with arms or hands. */
  case object BallManipulation extends Penalty { val code: Int = 1 }

  /** Illegal physical contact with an opponent. */
  case object PhysicalContact extends Penalty { val code: Int = 2 }

  /** An illegal attack under the kid-size rules. */
  case object IllegalAttack extends Penalty { val code: Int = 3 }

  /** An illegal defence under the kid-size rules. */
  case object IllegalDefense extends Penalty { val code: Int = 4 }

  /** The team asked to pick the robot up. */
  case object RequestForPickup extends Penalty { val code: Int = 5 }

  /** The team asked to service the robot. */
  case object RequestForService extends Penalty { val code: Int = 6 }

  /** A pick-up was turned into a service. */
  case object RequestForPickupToService extends Penalty { val code: Int = 7 }

  /** The player is a substitute, not on the field. */
  case object Substitute extends Penalty { val code: Int = 14 }

  /** Penalised by hand on the GameController (or by the robot's own return packet). */
  case object Manual extends Penalty { val code: Int = 15 }

  /** A value outside the known set; decoding produces it only for codes no known penalty has. */
  final case class Unknown(code: Int) extends Penalty

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

  /** The penalty with this wire value, or `Unknown(code)`. */
  def fromCode(code: Int): Penalty = known.find(_.code == code).getOrElse(Unknown(code))
}
