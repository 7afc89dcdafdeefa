package naogateway.sim

import java.net.{InetAddress, InetSocketAddress}

import scala.collection.immutable.ArraySeq
import scala.concurrent.duration._

import akka.actor.typed.scaladsl.{ActorContext, Behaviors}
import akka.actor.typed.{ActorRef, Behavior}

import naogateway.gateway.link.UdpLink
import naogateway.wire.gamecontroller._

/** Settings of a [[SimulatedGameController]].
  *
  * One cycle is a whole game of two halves; each half runs INITIAL, READY, SET, PLAYING and FINISHED for the given
  * durations. The half's clock (`secsRemaining`) starts at the PLAYING duration and counts down while PLAYING, so a
  * half ends with the clock at 0, as a real half does. Within PLAYING, `setPlayAfter` into it, the referee stops play
  * for `stoppedFor` (a goal kick for `teams[1]` is called: version 19 says `stopped` and the set play, version 12 the
  * set play) and the set play then runs for `setPlayFor` with play going on; the half's clock runs throughout. No set
  * play when they do not fit the PLAYING duration.
  *
  * @param target
  *   where the packets go: the gateway's GameController port (a real GameController broadcasts to 3838)
  * @param bindAddress
  *   the controller's own socket; port 0 lets the operating system pick one
  * @param team0
  *   the team number in the packets' `teams[0]` (blue)
  * @param team1
  *   the team number in `teams[1]` (red)
  * @param playersPerTeam
  *   the packets' `playersPerTeam` (6 in the humanoid KidSize league)
  * @param interval
  *   one round of packets this often; the real GameController sends two a second
  * @param version
  *   the GameController to play: 20 (the Humanoid Soccer League's of RoboCup 2026, the default), 19 (its GameController
  *   6, early 2026), 12 (the Humanoid League's until 2025), 8 (the 2014 one, which sends a version-8 and a version-7
  *   packet each round) or 7 (its version-7 packets alone)
  * @param messageBudget
  *   the version-20 and -19 `messageBudget` of both teams; the simulation hears no team message, so it stays
  * @param robots
  *   where the simulated robots receive (3838 on each robot's address): a real GameController broadcasts each round to
  *   the field, so the robots hear it as the gateway does (docs/protocol.md 6.9: a robot closes its bus bridge while
  *   the game runs); each gets the same packets as `target`
  */
final case class SimulatedGameControllerSettings(
    target: InetSocketAddress,
    bindAddress: InetSocketAddress = SimulatedRobotSettings.AnyLoopbackPort,
    team0: Int = 12,
    team1: Int = 7,
    playersPerTeam: Int = 6,
    initial: FiniteDuration = 5.seconds,
    ready: FiniteDuration = 5.seconds,
    set: FiniteDuration = 3.seconds,
    playing: FiniteDuration = 45.seconds,
    finished: FiniteDuration = 5.seconds,
    interval: FiniteDuration = 500.millis,
    version: GameControlVersion = GameControlVersion.V20,
    setPlayAfter: FiniteDuration = 20.seconds,
    stoppedFor: FiniteDuration = 3.seconds,
    setPlayFor: FiniteDuration = 5.seconds,
    messageBudget: Int = 12000,
    robots: Vector[InetSocketAddress] = Vector.empty
) {
  require(Seq(team0, team1, playersPerTeam).forall(n => n >= 0 && n <= 255), "team numbers and players must fit a byte")
  require(Seq(initial, ready, set, finished).forall(_ >= Duration.Zero), "phase durations must not be negative")
  require(playing > Duration.Zero, "the PLAYING phase must last")
  require(playing.toSeconds <= Short.MaxValue, "secsRemaining must fit the version-8 i16")
  require(interval >= 10.millis, "interval must be at least 10 ms")
  require(Seq(team0, team1).forall(_ != 255), "team number 255 means no team in versions 20, 19 and 12")
  require(messageBudget >= 0 && messageBudget <= 0xffff, "messageBudget must fit a u16")

  /** Whether PLAYING holds the stopped pause and the set play. */
  def hasSetPlay: Boolean = setPlayAfter + stoppedFor + setPlayFor < playing

  /** One half, INITIAL to the end of FINISHED. */
  def halfNanos: Long = (initial + ready + set + playing + finished).toNanos
}

/** The game as the simulated GameController sees it at one moment: what each round's packets say.
  *
  * @param stopped
  *   play is stopped by the referee (versions 20 and 19 say `stopped`)
  * @param setPlay
  *   the set play under way, taken by `teams[1]` (versions 20, 19 and 12 say it; 8 and 7 do not)
  */
final case class GameMoment(
    gameState: GameState,
    firstHalf: Boolean,
    kickOffTeam: KickOffTeam,
    secsRemaining: Long,
    secondaryTime: Int,
    stopped: Boolean = false,
    setPlay: SetPlay = SetPlay.NoSetPlay
)

/** A simulated RoboCup GameController on loopback: real `RGme` packets of the version its settings name (20 by default:
  * 158 bytes; 19: 198 bytes; 12: 688 bytes; 8: a version-8 and a version-7 packet each round, as 2014's GameController
  * broadcast them; 7: the version-7 packets alone), cycling INITIAL → READY → SET → PLAYING (with a stopped pause and a
  * set play) → FINISHED over both halves on the short schedule of its [[SimulatedGameControllerSettings]]. The demo
  * runs one against the gateway, so the game state and the competition gate can be seen without a field.
  *
  * The schedule and the packets are pure ([[SimulatedGameController.momentAt]], [[SimulatedGameController.packets]]);
  * the actor only wakes at each round's timer and sends.
  */
object SimulatedGameController {

  /** What the simulated GameController accepts; it runs on its own and needs no command from outside. */
  sealed trait Command

  private case object Round extends Command
  private final case class FromSocket(event: UdpLink.Event) extends Command

  private case object RoundKey

  /** Every field the simulation does not drive, as in the real packets: no score, nobody penalised, no drop-in. */
  private def team(number: Int, colour: TeamColour, version: GameControlVersion): TeamInfo = {
    val v8 = version == GameControlVersion.V8
    val player = PlayerInfo.Unpenalised
    TeamInfo(
      teamNumber = number,
      teamColour = colour,
      score = 0,
      // The humanoid leagues' version-7 packets carry yellow for both teams' goals.
      goalColour = if (v8) None else Some(GoalColour.Yellow),
      penaltyShot = if (v8) Some(0) else None,
      singleShots = if (v8) Some(0) else None,
      coachMessage = if (v8) Some(ArraySeq.fill[Byte](TeamInfo.CoachMessageBytes)(0)) else None,
      coach = if (v8) Some(player) else None,
      players = Vector.fill(TeamInfo.PlayerSlots)(player)
    )
  }

  /** Where the schedule stands `elapsedNanos` after the controller started (the first half's INITIAL). */
  def momentAt(settings: SimulatedGameControllerSettings, elapsedNanos: Long): GameMoment = {
    val half = math.max(0L, elapsedNanos) / settings.halfNanos
    val firstHalf = half % 2 == 0
    var t = math.max(0L, elapsedNanos) % settings.halfNanos
    val full = settings.playing.toSeconds
    // Whole seconds left of `d` after `t` of it, as the GameController's clocks show them (rounded up).
    def left(d: FiniteDuration, t: Long): Long = (d.toNanos - t + 999999999L) / 1000000000L
    val kickOff = if (firstHalf) KickOffTeam.Blue else KickOffTeam.Red
    def at(state: GameState, secs: Long, secondary: Long) = GameMoment(state, firstHalf, kickOff, secs, secondary.toInt)
    if (t < settings.initial.toNanos) at(GameState.Initial, full, 0)
    else {
      t -= settings.initial.toNanos
      if (t < settings.ready.toNanos) at(GameState.Ready, full, left(settings.ready, t))
      else {
        t -= settings.ready.toNanos
        if (t < settings.set.toNanos) at(GameState.Set, full, 0)
        else {
          t -= settings.set.toNanos
          if (t < settings.playing.toNanos) {
            val playing = at(GameState.Playing, left(settings.playing, t), 0)
            val stopAt = settings.setPlayAfter.toNanos
            val runAt = stopAt + settings.stoppedFor.toNanos
            val endAt = runAt + settings.setPlayFor.toNanos
            if (!settings.hasSetPlay || t < stopAt || t >= endAt) playing
            else if (t < runAt) playing.copy(stopped = true, setPlay = SetPlay.GoalKick)
            // The set play's own countdown runs on the secondary clock once play goes on.
            else
              playing.copy(setPlay = SetPlay.GoalKick, secondaryTime = ((endAt - t + 999999999L) / 1000000000L).toInt)
          } else at(GameState.Finished, 0, 0)
        }
      }
    }
  }

  /** The packet content of `moment` in `version`'s layout; `packetNumber` counts version-8 packets (wraps at 256). */
  def controlData(
      settings: SimulatedGameControllerSettings,
      version: GameControlVersion,
      moment: GameMoment,
      packetNumber: Int
  ): ControlData2014 = {
    val v8 = version == GameControlVersion.V8
    ControlData2014(
      version = version,
      packetNumber = if (v8) Some(packetNumber & 0xff) else None,
      playersPerTeam = settings.playersPerTeam,
      gameState = moment.gameState,
      firstHalf = moment.firstHalf,
      kickOffTeam = moment.kickOffTeam,
      secondaryGameState = SecondaryGameState.Normal,
      dropInTeam = TeamColour.Blue,
      dropInTime = -1,
      secsRemaining = moment.secsRemaining,
      secondaryTime = if (v8) Some(moment.secondaryTime) else None,
      team0 = team(settings.team0, TeamColour.Blue, version),
      team1 = team(settings.team1, TeamColour.Red, version)
    )
  }

  /** The team number of the team kicking off (by its colour) or taking the set play (always `teams[1]`). */
  private def kickingTeam(settings: SimulatedGameControllerSettings, moment: GameMoment): Int =
    if (moment.setPlay != SetPlay.NoSetPlay || moment.kickOffTeam == KickOffTeam.Red) settings.team1 else settings.team0

  /** The version-19 packet content of `moment`: players beyond `playersPerTeam` are substitutes, as the GameController
    * lists them.
    */
  def controlDataV19(
      settings: SimulatedGameControllerSettings, moment: GameMoment, packetNumber: Int): HslControlData = {
    def team(number: Int, colour: FieldColour, keeperColour: FieldColour) = HslTeamInfo(
      number,
      colour,
      keeperColour,
      goalkeeper = 1,
      score = 0,
      penaltyShot = 0,
      singleShots = 0,
      messageBudget = settings.messageBudget,
      players = Vector.tabulate(HslPlayerInfo.Slots)(i =>
        if (i < settings.playersPerTeam) HslPlayerInfo.Unpenalised else HslPlayerInfo(HslPenalty.Substitute, 0, 0, 0))
    )
    HslControlData(
      packetNumber & 0xff,
      settings.playersPerTeam,
      CompetitionType.Small,
      moment.stopped,
      GamePhase.Normal,
      moment.gameState,
      moment.setPlay,
      moment.firstHalf,
      Some(kickingTeam(settings, moment)),
      moment.secsRemaining,
      moment.secondaryTime,
      team(settings.team0, FieldColour.Blue, FieldColour.Yellow),
      team(settings.team1, FieldColour.Red, FieldColour.Black)
    )
  }

  /** The version-20 packet content of `moment`: version 19's, with version 20's team entries (players beyond
    * `playersPerTeam` are substitutes, penalty 13).
    */
  def controlDataV20(
      settings: SimulatedGameControllerSettings, moment: GameMoment, packetNumber: Int): Hsl20ControlData = {
    val v19 = controlDataV19(settings, moment, packetNumber)
    def team(t: HslTeamInfo) = Hsl20TeamInfo(
      t.teamNumber,
      t.fieldPlayerColour,
      t.goalkeeperColour,
      t.goalkeeper,
      t.score,
      t.penaltyShot,
      t.singleShots,
      t.messageBudget,
      Vector.tabulate(Hsl20PlayerInfo.Slots)(i =>
        if (i < settings.playersPerTeam) Hsl20PlayerInfo.Unpenalised
        else Hsl20PlayerInfo(Hsl20Penalty.Substitute, 0, 0))
    )
    Hsl20ControlData(
      v19.packetNumber,
      v19.playersPerTeam,
      v19.competitionType,
      v19.stopped,
      v19.gamePhase,
      v19.gameState,
      v19.setPlay,
      v19.firstHalf,
      v19.kickingTeam,
      v19.secsRemaining,
      v19.secondaryTime,
      team(v19.team0),
      team(v19.team1)
    )
  }

  /** The version-12 packet content of `moment`: player 1 the goalkeeper, players beyond `playersPerTeam` substitutes.
    */
  def controlDataV12(
      settings: SimulatedGameControllerSettings, moment: GameMoment, packetNumber: Int): HlControlData = {
    def team(number: Int, colour: FieldColour) = HlTeamInfo(
      number,
      colour,
      score = 0,
      penaltyShot = 0,
      singleShots = 0,
      coachSequence = 0,
      ArraySeq.fill[Byte](HlPlayerInfo.CoachMessageBytes)(0),
      HlPlayerInfo.Unpenalised,
      Vector.tabulate(HlPlayerInfo.Slots)(i =>
        if (i >= settings.playersPerTeam) HlPlayerInfo.Unpenalised.copy(penalty = HlPenalty.Substitute)
        else HlPlayerInfo.Unpenalised.copy(goalkeeper = i == 0))
    )
    val setPlay = moment.setPlay != SetPlay.NoSetPlay
    HlControlData(
      packetNumber & 0xff,
      settings.playersPerTeam,
      HlGameType.KidSize,
      moment.gameState,
      moment.firstHalf,
      Some(kickingTeam(settings, moment)),
      if (setPlay) HlSecondaryState.GoalKick else HlSecondaryState.Normal,
      ArraySeq[Byte](if (setPlay) settings.team1.toByte else 0, 0, 0, 0),
      dropInTeam = 0,
      dropInTime = 0xffff,
      moment.secsRemaining,
      moment.secondaryTime,
      team(settings.team0, FieldColour.Blue),
      team(settings.team1, FieldColour.Red)
    )
  }

  /** One round on the wire in the settings' version (version 8: the version-8 packet, then the version-7 one). */
  def packets(settings: SimulatedGameControllerSettings, moment: GameMoment, packetNumber: Int): Vector[Array[Byte]] = {
    val contents: Vector[GameControlData] = settings.version match {
      case GameControlVersion.V20 => Vector(controlDataV20(settings, moment, packetNumber))
      case GameControlVersion.V19 => Vector(controlDataV19(settings, moment, packetNumber))
      case GameControlVersion.V12 => Vector(controlDataV12(settings, moment, packetNumber))
      case GameControlVersion.V8 =>
        Vector(GameControlVersion.V8, GameControlVersion.V7).map(controlData(settings, _, moment, packetNumber))
      case GameControlVersion.V7 => Vector(controlData(settings, GameControlVersion.V7, moment, packetNumber))
    }
    // The settings' checks keep every field in range, so encoding cannot fail; if it did, that is a bug here.
    contents.map(c =>
      GameControllerCodec.encodeControl(c).fold(e => throw new IllegalStateException(e.describe), identity))
  }

  /** A controller sending to `settings.target` and `settings.robots` from a socket of its own, until it is stopped. */
  def apply(settings: SimulatedGameControllerSettings): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        val fromSocket = context.messageAdapter[UdpLink.Event](FromSocket.apply)
        context.spawn(UdpLink(settings.bindAddress, fromSocket), "udp")
        Behaviors.receiveMessage {
          case FromSocket(UdpLink.Bound(link, local)) =>
            context.log.info("Simulated GameController on {} sends to {} and {} robot(s)", local, settings.target,
              settings.robots.size.toString)
            timers.startTimerAtFixedRate(RoundKey, Round, settings.interval)
            new Running(settings, context, link, System.nanoTime()).sending(packetNumber = 1, shown = None)
          case FromSocket(UdpLink.BindFailed(address, reason)) =>
            context.log.warn("Simulated GameController cannot bind {}: {}", address, reason)
            Behaviors.stopped
          case FromSocket(_) | Round =>
            Behaviors.same
        }
      }
    }

  private final class Running(
      settings: SimulatedGameControllerSettings,
      context: ActorContext[Command],
      link: ActorRef[UdpLink.Command],
      origin: Long
  ) {
    // The first round goes out at once; later ones on the timer.
    def sending(packetNumber: Int, shown: Option[(GameState, Boolean, SetPlay)]): Behavior[Command] = {
      val moment = momentAt(settings, System.nanoTime() - origin)
      // As one broadcast reaches every host on the field: the same packets to the gateway and to each robot.
      for (p <- packets(settings, moment, packetNumber); to <- settings.target +: settings.robots)
        link ! UdpLink.Send(p, to)
      val now = (moment.gameState, moment.stopped, moment.setPlay)
      if (!shown.contains(now))
        context.log.info(
          "Simulated GameController (version {}): {}{} ({} half)",
          settings.version.number.toString,
          moment.gameState,
          (if (moment.stopped) ", stopped" else "") + (if (moment.setPlay != SetPlay.NoSetPlay) s", ${moment.setPlay}"
                                                       else ""),
          if (moment.firstHalf) "first" else "second"
        )
      waiting((packetNumber + 1) & 0xff, Some(now))
    }

    private def waiting(packetNumber: Int, shown: Option[(GameState, Boolean, SetPlay)]): Behavior[Command] =
      Behaviors.receiveMessage {
        case Round => sending(packetNumber, shown)
        // Anything arriving on the controller's socket (robots' return packets) is not needed here.
        case FromSocket(_) => Behaviors.same
      }
  }

  /** `127.0.0.1` at `port`: where the demo's controller sends when the gateway listens on every address. */
  def loopback(port: Int): InetSocketAddress = new InetSocketAddress(InetAddress.getLoopbackAddress, port)
}
