package naogateway.wire.gamecontroller

/** The main state of a game as the GameController broadcasts it (`state`, one byte in both versions). */
sealed abstract class GameState(val code: Int) extends WireCode

/** Game states known to versions 7 and 8; any other byte is kept as `Unknown` so nothing is lost. */
object GameState extends WireCodes[GameState] {

  /** Robots stand still and wait; the game has not started. */
  case object Initial extends GameState(0)

  /** Robots walk to their kick-off positions. */
  case object Ready extends GameState(1)

  /** Robots hold their positions until the whistle. */
  case object Set extends GameState(2)

  /** The ball is in play. */
  case object Playing extends GameState(3)

  /** The half (or game) is over. */
  case object Finished extends GameState(4)

  /** A value outside the known set; decoding produces it only for codes no known state has. */
  final case class Unknown(override val code: Int) extends GameState(code)

  /** The known states, in code order. */
  val known: Seq[GameState] = Seq(Initial, Ready, Set, Playing, Finished)
  protected def unknown(code: Int): GameState = Unknown(code)
}

/** Extra information on the game's phase (`secondaryState`, one byte in both versions). */
sealed abstract class SecondaryGameState(val code: Int) extends WireCode

/** Secondary states known to versions 7 and 8 (version 7 has no `Timeout`). */
object SecondaryGameState extends WireCodes[SecondaryGameState] {

  /** Regular play. */
  case object Normal extends SecondaryGameState(0)

  /** A penalty shoot-out. */
  case object PenaltyShoot extends SecondaryGameState(1)

  /** Extra time after a drawn game. */
  case object Overtime extends SecondaryGameState(2)

  /** A team has called a time-out (version 8). */
  case object Timeout extends SecondaryGameState(3)

  /** A value outside the known set; decoding produces it only for codes no known state has. */
  final case class Unknown(override val code: Int) extends SecondaryGameState(code)

  /** The known states, in code order. */
  val known: Seq[SecondaryGameState] = Seq(Normal, PenaltyShoot, Overtime, Timeout)
  protected def unknown(code: Int): SecondaryGameState = Unknown(code)
}
