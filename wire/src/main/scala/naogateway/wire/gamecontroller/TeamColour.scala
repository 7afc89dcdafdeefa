package naogateway.wire.gamecontroller

/** The colour a team plays in (`teamColour`, and the team that caused the last drop-in). */
sealed trait TeamColour extends Product with Serializable {

  /** The value on the wire. */
  def code: Int
}

/** Team colours of versions 7 and 8 (the humanoid league's cyan and magenta share blue's and red's codes). */
object TeamColour {

  /** Blue (cyan), code 0. */
  case object Blue extends TeamColour { val code: Int = 0 }

  /** Red (magenta), code 1. */
  case object Red extends TeamColour { val code: Int = 1 }

  /** A value outside the known set; decoding produces it only for codes no known colour has. */
  final case class Unknown(code: Int) extends TeamColour

  /** The known colours, in code order. */
  val known: Seq[TeamColour] = Seq(Blue, Red)

  /** The colour with this wire value, or `Unknown(code)`. */
  def fromCode(code: Int): TeamColour = known.find(_.code == code).getOrElse(Unknown(code))
}

/** Who kicks off next (`kickOffTeam`): a team by its colour, or nobody because of a dropped ball. */
sealed trait KickOffTeam extends Product with Serializable {

  /** The value on the wire. */
  def code: Int
}

/** Kick-off values of versions 7 and 8. */
object KickOffTeam {

  /** The blue team kicks off. */
  case object Blue extends KickOffTeam { val code: Int = 0 }

  /** The red team kicks off. */
  case object Red extends KickOffTeam { val code: Int = 1 }

  /** The game restarts with a dropped ball; neither team kicks off. */
  case object DropBall extends KickOffTeam { val code: Int = 2 }

  /** A value outside the known set; decoding produces it only for codes no known value has. */
  final case class Unknown(code: Int) extends KickOffTeam

  /** The known values, in code order. */
  val known: Seq[KickOffTeam] = Seq(Blue, Red, DropBall)

  /** The value with this wire code, or `Unknown(code)`. */
  def fromCode(code: Int): KickOffTeam = known.find(_.code == code).getOrElse(Unknown(code))
}

/** The colour of the goal a team defends (`goalColour`, version 7 only). */
sealed trait GoalColour extends Product with Serializable {

  /** The value on the wire. */
  def code: Int
}

/** Goal colours of version 7. */
object GoalColour {

  /** Blue goal, code 0. */
  case object Blue extends GoalColour { val code: Int = 0 }

  /** Yellow goal, code 1. */
  case object Yellow extends GoalColour { val code: Int = 1 }

  /** A value outside the known set; decoding produces it only for codes no known colour has. */
  final case class Unknown(code: Int) extends GoalColour

  /** The known colours, in code order. */
  val known: Seq[GoalColour] = Seq(Blue, Yellow)

  /** The colour with this wire value, or `Unknown(code)`. */
  def fromCode(code: Int): GoalColour = known.find(_.code == code).getOrElse(Unknown(code))
}
