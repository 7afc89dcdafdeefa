package naogateway.sim

import java.net.InetSocketAddress

import naogateway.wire.gamecontroller.{
  GameControlData,
  GameControlVersion,
  GameControllerCodec,
  GameState,
  ReturnData,
  ReturnMessage,
  ReturnStatus
}

/** The simulated firmware and the GameController (docs/protocol.md 10.10): what it keeps of a control packet, what it
  * answers, and whether the game runs for the bus bridge. Pure, beside [[RobotFirmware]].
  */
private[sim] object FirmwareGame {

  /** The firmware after control packet `data` from `from`, and its answer to the GameController, if it sends one. */
  def onGameController(
      s: FirmwareState, data: GameControlData, from: InetSocketAddress): (FirmwareState, Vector[Outgoing]) =
    if (s.settings.gameControllerSource.exists(_ != from.getAddress))
      // Another host's control packet changes nothing: not the game state, the bus gate or an answer (counted).
      (s.copy(stats = s.stats.copy(gameControllerIgnored = s.stats.gameControllerIgnored + 1)), Vector.empty)
    else heard(s, data, from)

  private def heard(
      s: FirmwareState, data: GameControlData, from: InetSocketAddress): (FirmwareState, Vector[Outgoing]) = {
    val counted =
      s.copy(game = Some(data), stats = s.stats.copy(gameControllerPackets = s.stats.gameControllerPackets + 1))
    // A robot answers the GameController it heard, as robots of that version do: the 2014 one (version 8; its
    // version-7 copy of the round needs no second answer) with RGrt version 2 to port 3838; the Humanoid League's
    // (version 12) with RGrt version 2 to 3939; the Humanoid Soccer League's (versions 20 and 19) with its status
    // message, RGrt version 4, to 3939.
    if (data.teamByNumber(s.settings.teamId).isEmpty) (counted, Vector.empty)
    else {
      def alive =
        GameControllerCodec.encodeReturn(ReturnData(s.settings.teamId, s.settings.playerNumber, ReturnMessage.Alive))
          .toOption
      val answer = data.version match {
        case GameControlVersion.V8 =>
          alive.map(_ -> 3838)
        case GameControlVersion.V12 =>
          alive.map(_ -> GameControllerCodec.ReturnPort)
        case GameControlVersion.V20 | GameControlVersion.V19 =>
          val (ahead, left) = s.pose.relative(s.settings.scene.ballX, s.settings.scene.ballY)
          val status = ReturnStatus(
            s.settings.playerNumber,
            s.settings.teamId,
            fallen = false,
            ((s.pose.x * 1000).toFloat, (s.pose.y * 1000).toFloat, s.pose.theta.toFloat),
            ballAge = 0f,
            ((ahead * 1000).toFloat, (left * 1000).toFloat)
          )
          GameControllerCodec.encodeStatus(status).toOption.map(_ -> GameControllerCodec.ReturnPort)
        case GameControlVersion.V7 => None
      }
      val to = (port: Int) => Destination.ReplyTo(new InetSocketAddress(from.getAddress, port))
      (counted, answer.map { case (b, port) => Outgoing(b, to(port)) }.toVector)
    }
  }

  /** Whether the GameController packet the robot uses says the game runs (READY, SET, PLAYING): the bus bridge is
    * closed then (docs/protocol.md 6.9).
    */
  def gameRunning(s: FirmwareState): Boolean =
    s.game.exists(g =>
      g.gameState == GameState.Ready || g.gameState == GameState.Set || g.gameState == GameState.Playing)
}
