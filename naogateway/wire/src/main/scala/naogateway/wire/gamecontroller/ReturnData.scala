package naogateway.wire.gamecontroller

/** What a robot tells the GameController in an `RGrt` return packet. */
sealed abstract class ReturnMessage(val code: Int) extends WireCode

/** Messages of return-packet version 2. */
object ReturnMessage extends WireCodes[ReturnMessage] {

  /** The robot penalised itself (e.g. its button was pressed). */
  case object ManualPenalise extends ReturnMessage(0)

  /** The robot lifted its own manual penalty. */
  case object ManualUnpenalise extends ReturnMessage(1)

  /** The robot is alive and receiving control packets. */
  case object Alive extends ReturnMessage(2)

  /** A value outside the known set; decoding produces it only for codes no known message has. */
  final case class Unknown(override val code: Int) extends ReturnMessage(code)

  /** The known messages, in code order. */
  val known: Seq[ReturnMessage] = Seq(ManualPenalise, ManualUnpenalise, Alive)
  protected def unknown(code: Int): ReturnMessage = Unknown(code)
}

/** The content of an `RGrt` return packet (version 2, 8 bytes).
  *
  * @param team
  *   the robot's team number
  * @param player
  *   the robot's player number, counted from 1
  */
final case class ReturnData(team: Int, player: Int, message: ReturnMessage)

/** The content of an `RGrt` return packet of version 4 (32 bytes), the status message a robot sends the version-19
  * GameController on UDP 3939. Note the order: player, then team (version 2 has team, then player).
  *
  * @param player
  *   the robot's player number, counted from 1
  * @param fallen
  *   whether the robot is fallen (the wire's 1; 0 means it can play)
  * @param pose
  *   x and y in mm from the field's centre, theta in radians
  * @param ballAge
  *   seconds since the robot last saw the ball; −1 if it never did
  * @param ball
  *   the ball's x and y in mm relative to the robot
  */
final case class ReturnStatus(
    player: Int,
    team: Int,
    fallen: Boolean,
    pose: (Float, Float, Float),
    ballAge: Float,
    ball: (Float, Float)
)
