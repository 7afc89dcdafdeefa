package naogateway.wire.gamecontroller

/** The colour a team plays in (`teamColour`, and the team that caused the last drop-in). */
sealed abstract class TeamColour(val code: Int) extends WireCode

/** Team colours of versions 7 and 8 (the humanoid league's cyan and magenta share blue's and red's codes). */
object TeamColour extends WireCodes[TeamColour] {

  /** Blue (cyan), code 0. */
  case object Blue extends TeamColour(0)

  /** Red (magenta), code 1. */
  case object Red extends TeamColour(1)

  /** A value outside the known set; decoding produces it only for codes no known colour has. */
  final case class Unknown(override val code: Int) extends TeamColour(code)

  /** The known colours, in code order. */
  val known: Seq[TeamColour] = Seq(Blue, Red)
  protected def unknown(code: Int): TeamColour = Unknown(code)
}

/** Who kicks off next (`kickOffTeam`): a team by its colour, or nobody because of a dropped ball. */
sealed abstract class KickOffTeam(val code: Int) extends WireCode

/** Kick-off values of versions 7 and 8. */
object KickOffTeam extends WireCodes[KickOffTeam] {

  /** The blue team kicks off. */
  case object Blue extends KickOffTeam(0)

  /** The red team kicks off. */
  case object Red extends KickOffTeam(1)

  /** The game restarts with a dropped ball; neither team kicks off. */
  case object DropBall extends KickOffTeam(2)

  /** A value outside the known set; decoding produces it only for codes no known value has. */
  final case class Unknown(override val code: Int) extends KickOffTeam(code)

  /** The known values, in code order. */
  val known: Seq[KickOffTeam] = Seq(Blue, Red, DropBall)
  protected def unknown(code: Int): KickOffTeam = Unknown(code)
}

/** The colour of the goal a team defends (`goalColour`, version 7 only). */
sealed abstract class GoalColour(val code: Int) extends WireCode

/** Goal colours of version 7. */
object GoalColour extends WireCodes[GoalColour] {

  /** Blue goal, code 0. */
  case object Blue extends GoalColour(0)

  /** Yellow goal, code 1. */
  case object Yellow extends GoalColour(1)

  /** A value outside the known set; decoding produces it only for codes no known colour has. */
  final case class Unknown(override val code: Int) extends GoalColour(code)

  /** The known colours, in code order. */
  val known: Seq[GoalColour] = Seq(Blue, Yellow)
  protected def unknown(code: Int): GoalColour = Unknown(code)
}
