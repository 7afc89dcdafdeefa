package naogateway.wire.gamecontroller

/** The main state of a game as the GameController broadcasts it (`state`, one byte in both versions). */
sealed trait GameState extends Product with Serializable {

  /** The value on the wire. */
  def code: Int
}

/** Game states known to versions 7 and 8; any other byte is kept as `Unknown` so nothing is lost. */
object GameState {

  /** Robots stand still and wait; the game has not started. */
  case object Initial extends GameState { val code: Int = 0 }

  /** Robots walk to their kick-off positions. */
  case object Ready extends GameState { val code: Int = 1 }

  /** Robots hold their positions until the whistle. */
  case object Set extends GameState { val code: Int = 2 }

  /** The ball is in play. */
  case object Playing extends GameState { val code: Int = 3 }

  /** The half (or game) is over. */
  case object Finished extends GameState { val code: Int = 4 }

  /** A value outside the known set; decoding produces it only for codes no known state has. */
  final case class Unknown(code: Int) extends GameState

  /** The known states, in code order. */
  val known: Seq[GameState] = Seq(Initial, Ready, Set, Playing, Finished)

  /** The state with this wire value, or `Unknown(code)`. */
  def fromCode(code: Int): GameState = known.find(_.code == code).getOrElse(Unknown(code))
}

/** Extra information on the game's phase (`secondaryState`, one byte in both versions). */
sealed trait SecondaryGameState extends Product with Serializable {

  /** The value on the wire. */
  def code: Int
}

/** Secondary states known to versions 7 and 8 (version 7 has no `Timeout`). */
object SecondaryGameState {

  /** Regular play. */
  case object Normal extends SecondaryGameState { val code: Int = 0 }

  /** A penalty shoot-out. */
  case object PenaltyShoot extends SecondaryGameState { val code: Int = 1 }

  /** Extra time after a drawn game. */
  case object Overtime extends SecondaryGameState { val code: Int = 2 }

  /** A team has called a time-out (version 8). */
  case object Timeout extends SecondaryGameState { val code: Int = 3 }

  /** A value outside the known set; decoding produces it only for codes no known state has. */
  final case class Unknown(code: Int) extends SecondaryGameState

  /** The known states, in code order. */
  val known: Seq[SecondaryGameState] = Seq(Normal, PenaltyShoot, Overtime, Timeout)

  /** The state with this wire value, or `Unknown(code)`. */
  def fromCode(code: Int): SecondaryGameState = known.find(_.code == code).getOrElse(Unknown(code))
}
