package naogateway.gateway.recording

import naogateway.wire.gamecontroller.{GameControlData, GameState}

/** When the recording begins and ends a game's file (docs/recording.md): with a GameController, one file per half,
  * begun at the half's first READY and ended at its FINISHED, or once no GameController packet came for `quietNanos`;
  * named by the teams and the half. Pure; the recorder's writer thread holds one and feeds it the game-state entries it
  * writes and the time.
  *
  * @param half
  *   the half being recorded, if one is
  * @param lastPacket
  *   when the last GameController packet was written (the gateway's clock)
  */
final case class GameFiles(quietNanos: Long, half: Option[GameFiles.Half] = None, lastPacket: Option[Long] = None) {
  import GameFiles._

  /** A GameController packet written at `nowNanos`: what to do with the files. */
  def packet(data: GameControlData, nowNanos: Long): (GameFiles, Vector[Step]) = {
    val seen = copy(lastPacket = Some(nowNanos))
    val thisHalf = Half(data.team0.teamNumber, data.team1.teamNumber, data.firstHalf)
    half match {
      case Some(h) if data.gameState == GameState.Finished =>
        (seen.copy(half = None), Vector(End(s"${h.label} finished")))
      case Some(h) if h != thisHalf && data.gameState == GameState.Ready =>
        // The next half (or game) began without a FINISHED heard.
        (seen.copy(half = Some(thisHalf)), Vector(End(s"${h.label} over: ${thisHalf.label} began"), Begin(thisHalf)))
      case Some(h) if h != thisHalf                  => (seen.copy(half = None), Vector(End(s"${h.label} over")))
      case Some(_)                                   => (seen, Vector.empty)
      case None if data.gameState == GameState.Ready => (seen.copy(half = Some(thisHalf)), Vector(Begin(thisHalf)))
      case None                                      => (seen, Vector.empty)
    }
  }

  /** The time passing: a half whose GameController has gone quiet for `quietNanos` ends. */
  def tick(nowNanos: Long): (GameFiles, Vector[Step]) = (half, lastPacket) match {
    case (Some(h), Some(at)) if nowNanos - at >= quietNanos =>
      (copy(half = None), Vector(End(s"${h.label}: no GameController packet for ${quietNanos / 1000000000L} s")))
    case _ => (this, Vector.empty)
  }
}

/** The steps and halves of [[GameFiles]]. */
object GameFiles {

  /** One half of a game: its teams (as the wire's `teams[0]` and `teams[1]`) and whether it is the first. */
  final case class Half(team0: Int, team1: Int, firstHalf: Boolean) {

    /** The part of the file name that says which half of which game: `team12-vs-team7-half1`. */
    def label: String = s"team$team0-vs-team$team1-half${if (firstHalf) 1 else 2}"
  }

  /** What the recorder does. */
  sealed trait Step extends Product with Serializable

  /** Closes the file and begins one for `half`. */
  final case class Begin(half: Half) extends Step

  /** Closes the half's file; files begun after it are named as without a game. */
  final case class End(reason: String) extends Step

  /** The file name of the `n`-th file, begun at `time` (yyyyMMdd-HHmmss), during `half` if one is recorded. */
  def fileName(time: String, half: Option[Half], n: Long): String =
    s"naogateway-$time${half.fold("")(h => s"-${h.label}")}-$n.mcap"
}
