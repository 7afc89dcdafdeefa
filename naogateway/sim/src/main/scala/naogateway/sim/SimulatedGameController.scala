package naogateway.sim

import java.net.{InetAddress, InetSocketAddress}

import scala.collection.immutable.ArraySeq
import scala.concurrent.duration._

import akka.actor.typed.scaladsl.{ActorContext, Behaviors}
import akka.actor.typed.{ActorRef, Behavior}

import naogateway.link.UdpLink
import naogateway.wire.gamecontroller._

/** Settings of a [[SimulatedGameController]].
  *
  * One cycle is a whole game of two halves; each half runs INITIAL, READY, SET, PLAYING and FINISHED for the given
  * durations. The half's clock (`secsRemaining`) starts at the PLAYING duration and counts down while PLAYING, so a
  * half ends with the clock at 0, as a real half does.
  *
  * @param target where the packets go: the gateway's GameController port (a real GameController broadcasts to 3838)
  * @param bindAddress the controller's own socket; port 0 lets the operating system pick one
  * @param team0 the team number in the packets' `teams[0]` (blue)
  * @param team1 the team number in `teams[1]` (red)
  * @param playersPerTeam the packets' `playersPerTeam` (6 in the humanoid KidSize league)
  * @param interval one round of packets (version 8, then version 7) this often; the real GameController sends two a
  *   second
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
    interval: FiniteDuration = 500.millis
) {
  require(Seq(team0, team1, playersPerTeam).forall(n => n >= 0 && n <= 255), "team numbers and players must fit a byte")
  require(Seq(initial, ready, set, finished).forall(_ >= Duration.Zero), "phase durations must not be negative")
  require(playing > Duration.Zero, "the PLAYING phase must last")
  require(playing.toSeconds <= Short.MaxValue, "secsRemaining must fit the version-8 i16")
  require(interval >= 10.millis, "interval must be at least 10 ms")

  /** One half, INITIAL to the end of FINISHED. */
  def halfNanos: Long = (initial + ready + set + playing + finished).toNanos
}

/** The game as the simulated GameController sees it at one moment: what each round's packets say. */
final case class GameMoment(
    gameState: GameState,
    firstHalf: Boolean,
    kickOffTeam: KickOffTeam,
    secsRemaining: Long,
    secondaryTime: Int
)

/** A simulated RoboCup GameController on loopback: real `RGme` packets of version 8 (158 bytes) and version 7
  * (116 bytes) each round, as the humanoid leagues' GameController broadcasts them, cycling INITIAL → READY → SET →
  * PLAYING → FINISHED on the short schedule of its [[SimulatedGameControllerSettings]]. The demo runs one against the
  * gateway, so the game state and the competition gate can be seen without a field.
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
          if (t < settings.playing.toNanos) at(GameState.Playing, left(settings.playing, t), 0)
          else at(GameState.Finished, 0, 0)
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

  /** One round on the wire: the version-8 packet, then the version-7 packet of the same moment. */
  def packets(settings: SimulatedGameControllerSettings, moment: GameMoment, packetNumber: Int): Vector[Array[Byte]] =
    Vector(GameControlVersion.V8, GameControlVersion.V7).map { version =>
      // The settings' checks keep every field in range, so encoding cannot fail; if it did, that is a bug here.
      GameControllerCodec
        .encodeControl(controlData(settings, version, moment, packetNumber))
        .fold(e => throw new IllegalStateException(e.describe), identity)
    }

  /** A controller sending to `settings.target` from a socket of its own, until it is stopped. */
  def apply(settings: SimulatedGameControllerSettings): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        val fromSocket = context.messageAdapter[UdpLink.Event](FromSocket.apply)
        context.spawn(UdpLink(settings.bindAddress, fromSocket), "udp")
        Behaviors.receiveMessage {
          case FromSocket(UdpLink.Bound(link, local)) =>
            context.log.info("Simulated GameController on {} sends to {}", local, settings.target)
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
    def sending(packetNumber: Int, shown: Option[GameState]): Behavior[Command] = {
      val moment = momentAt(settings, System.nanoTime() - origin)
      packets(settings, moment, packetNumber).foreach(link ! UdpLink.Send(_, settings.target))
      if (!shown.contains(moment.gameState))
        context.log.info("Simulated GameController: {} ({} half)", moment.gameState,
          if (moment.firstHalf) "first" else "second")
      waiting((packetNumber + 1) & 0xff, Some(moment.gameState))
    }

    private def waiting(packetNumber: Int, shown: Option[GameState]): Behavior[Command] =
      Behaviors.receiveMessage {
        case Round => sending(packetNumber, shown)
        // Anything arriving on the controller's socket (robots' return packets) is not needed here.
        case FromSocket(_) => Behaviors.same
      }
  }

  /** `127.0.0.1` at `port`: where the demo's controller sends when the gateway listens on every address. */
  def loopback(port: Int): InetSocketAddress = new InetSocketAddress(InetAddress.getLoopbackAddress, port)
}
