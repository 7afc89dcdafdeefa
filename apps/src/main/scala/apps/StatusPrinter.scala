package apps

import scala.concurrent.Future
import scala.concurrent.duration._
import scala.util.{Failure, Success}

import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{Behavior, PostStop, SupervisorStrategy}
import com.typesafe.config.Config

import naogateway.wire.gamecontroller.GameControlData
import naogateway.api.{GameSource, GatewayStats, GatewayView, Printable, RobotLinks, RobotSnapshot, TrafficStats}
import robotmiddleware.ServoLimits

/** Prints the launcher's status: a redrawn screen on a terminal, one line per change otherwise. */
object StatusPrinter {

  /** What the printer accepts. */
  sealed trait Command
  private case object Refresh extends Command
  private final case class Robots(robots: Vector[RobotSnapshot]) extends Command
  private final case class Traffic(stats: TrafficStats) extends Command
  private final case class Game(game: Option[GameControlData]) extends Command
  private final case class Source(source: GameSource) extends Command
  private final case class Links(links: RobotLinks) extends Command
  private final case class Stats(stats: GatewayStats) extends Command
  // A question the gateway did not answer: the figures shown stay as they were until the next refresh.
  private case object Unanswered extends Command

  /** How the status is shown: chosen from the terminal (`Auto`), or forced. */
  sealed trait ViewMode extends Product with Serializable

  /** The choices of `apps.launcher.view`. */
  object ViewMode {

    /** A screen on a terminal, lines otherwise. */
    case object Auto extends ViewMode

    /** Always the redrawn screen. */
    case object Screen extends ViewMode

    /** Always one line per change. */
    case object Lines extends ViewMode

    /** The mode named `name` (auto, screen or lines). */
    def parse(name: String): ViewMode = name.trim.toLowerCase match {
      case "auto"   => Auto
      case "screen" => Screen
      case "lines"  => Lines
      case other =>
        throw new IllegalArgumentException(s"apps.launcher.view must be auto, screen or lines, not '$other'")
    }
  }

  /** Where the printer writes. */
  sealed trait Output

  /** Lines appended one after the other, to a pipe or a log. */
  final case class LineOutput(writeLine: String => Unit) extends Output

  /** A screen the printer redraws as a whole. */
  trait ScreenOutput extends Output {

    /** Replaces what the screen shows with `lines` (fitted to the screen's size by the implementation). */
    def draw(lines: Vector[String]): Unit

    /** Gives the terminal back: the cursor below the screen, resources released. */
    def close(): Unit
  }

  /** The printer's settings (`apps.launcher`). */
  final case class Settings(refresh: FiniteDuration, view: ViewMode) {
    require(refresh >= 50.millis, "apps.launcher.refresh must be at least 50 ms")
  }

  /** The settings of an `apps.launcher` block. */
  def settings(c: Config): Settings =
    Settings(c.getDuration("refresh").toNanos.nanos, ViewMode.parse(c.getString("view")))

  /** The printer of the `apps.launcher` block `c`, writing where its `view` says; `notes` are lines shown above the
    * status (the web view's address once it listens), printed once each in line mode.
    */
  def fromConfig(gateway: GatewayView, c: Config, notes: () => Vector[String] = () => Vector.empty,
      servoLimits: ServoLimits = ServoLimits()): Behavior[Command] = {
    val s = settings(c)
    apply(gateway, s.refresh, output(s.view), notes, servoLimits)
  }

  /** Whether stdout is a terminal: `System.console()` in a JVM started on one, or what sbt says through
    * `NAOGATEWAY_TERMINAL` when it forks the launcher with its stdout as a pipe.
    */
  def onTerminal(env: String => Option[String] = sys.env.get): Boolean =
    System.console() != null || env("NAOGATEWAY_TERMINAL").exists(_.trim.equalsIgnoreCase("true"))

  /** The output `mode` asks for: a JLine screen on a terminal, `println` lines otherwise. */
  def output(mode: ViewMode): Output = {
    val screen = mode match {
      case ViewMode.Screen => true
      case ViewMode.Lines  => false
      case ViewMode.Auto   => onTerminal()
    }
    if (screen) TerminalScreen.open() else LineOutput(line => println(line))
  }

  /** A printer polling the gateway's read-only view every `refresh` and writing to `output`, marking servos by
    * `servoLimits`. It restarts (after a back-off, so a failure repeating every refresh cannot flood the log) on any
    * failure.
    */
  def apply(gateway: GatewayView, refresh: FiniteDuration, output: Output,
      notes: () => Vector[String] = () => Vector.empty, servoLimits: ServoLimits = ServoLimits()): Behavior[Command] =
    Behaviors.supervise(printer(gateway, refresh, output, notes, servoLimits)).onFailure[Exception](
      SupervisorStrategy.restartWithBackoff(1.second, 30.seconds, 0.2))

  /** How often the printer asks the gateway: every `refresh` for a screen; for lines, which only print changes, at most
    * once a second (each round asks the gateway five or six questions, and the robot actors with two of them).
    */
  private[apps] def pace(refresh: FiniteDuration, output: Output): FiniteDuration = output match {
    case _: ScreenOutput => refresh
    case _               => refresh.max(LinesRefresh)
  }

  /** The shortest pace of line output. */
  private[apps] val LinesRefresh: FiniteDuration = 1.second

  private def printer(gateway: GatewayView, refresh: FiniteDuration, output: Output, notes: () => Vector[String],
      servoLimits: ServoLimits): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        timers.startTimerWithFixedDelay(Refresh, pace(refresh, output))
        def ask[T](question: Future[T])(answer: T => Command): Unit =
          context.pipeToSelf(question) {
            case Success(a) => answer(a)
            case Failure(_) => Unanswered
          }

        val onScreen = output.isInstanceOf[ScreenOutput]
        // The questions of one round: robots, links, traffic, game state, game source, and the stats for a screen.
        val questions = if (onScreen) 6 else 5
        var notesShown = Vector.empty[String]
        def show(shown: StatusModel, model: StatusModel): Unit = output match {
          // Robots' and peers' strings are in these lines: no control character reaches the terminal.
          case screen: ScreenOutput => screen.draw((notes() ++ StatusView.render(model)).map(Printable.text))
          case LineOutput(write) =>
            val now = notes()
            now.filterNot(notesShown.contains).foreach(l => write(Printable.text(l)))
            notesShown = now
            StatusView.changes(shown, model).foreach(l => write(Printable.text(l)))
        }

        /* A round asks the gateway its questions and shows the model once every answer of the round is in (a question
         * that failed counts as answered), so a change shows as soon as the gateway has it, not a round later. A round
         * still waiting when the next begins (a gateway slower than the pace) is shown then, as it stands. */
        def running(model: StatusModel, shown: StatusModel, waiting: Int): Behavior[Command] = {
          def answered(next: StatusModel): Behavior[Command] =
            if (waiting > 1) running(next, shown, waiting - 1)
            else {
              if (waiting == 1) show(shown, next)
              running(next, next, 0)
            }
          Behaviors.receiveMessage[Command] {
            case Refresh =>
              if (waiting > 0) show(shown, model)
              ask(gateway.robots())(Robots.apply)
              ask(gateway.links())(Links.apply)
              ask(gateway.traffic())(Traffic.apply)
              ask(gateway.gameState())(Game.apply)
              ask(gateway.gameSource())(Source.apply)
              // The recording's figures are on the screen only; the lines never print them.
              if (onScreen) ask(gateway.stats())(Stats.apply)
              running(model, model, questions)
            case Robots(robots) => answered(model.copy(robots = robots))
            case Traffic(stats) => answered(model.copy(traffic = Some(stats)))
            case Game(game)     => answered(model.copy(game = game))
            case Source(source) => answered(model.copy(gameSource = Some(source)))
            case Stats(stats)   => answered(model.copy(gateway = Some(stats)))
            // The link figures of robots the gateway no longer knows are dropped with them.
            case Links(l)   => answered(model.copy(links = l.links.map(s => s.robotId -> s).toMap))
            case Unanswered => answered(model)
          }.receiveSignal { case (_, PostStop) =>
            output match {
              case screen: ScreenOutput => screen.close()
              case _: LineOutput        => ()
            }
            Behaviors.same
          }
        }

        val empty = StatusModel.empty.copy(servoLimits = servoLimits)
        running(empty, empty, 0)
      }
    }
}
