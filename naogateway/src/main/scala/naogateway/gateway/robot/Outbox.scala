package naogateway.gateway.robot

import java.net.InetSocketAddress

import scala.collection.immutable.Queue
import scala.concurrent.duration._

import akka.actor.typed.scaladsl.{Behaviors, TimerScheduler}
import akka.actor.typed.{ActorRef, Behavior}

import naogateway.gateway.link.ZeroMqRobotLink
import naogateway.transport.{DatagramWriter, PortLoop}
import naogateway.api.recording.Decision
import naogateway.gateway.tap.Tap
import naogateway.wire.{FrameSigning, WireLimits}
import naogateway.wire.gamecontroller.GameState
import naogateway.api.{GameReading, Priority, TrafficStats}
import naogateway.gateway.{BudgetSettings, GatewaySigning}
import naogateway.gateway.gamecontroller.CompetitionGate
import naogateway.transport.RateLimitedLog
import naogateway.gateway.SignRefusal

/** The last gate before the air, for both transports: the competition rule (applied here alone), the team's traffic
  * budget and the priority classes. Every robot's sender (`NoResponseActor`) sends through it.
  */
object Outbox {

  /** What the outbox accepts. */
  sealed trait Command

  /** Sends `bytes` to robot `robotId` at `to`; `replyTo`, when given, learns the outcome, marked with `tag`. `signed`:
    * `bytes` is an unsigned FU-Remote frame of a robot that must sign, signed here at the moment it leaves. `via`: a
    * ZeroMQ robot's link, which takes the bytes instead of the datagram socket, behind the same gate and budget.
    */
  private[naogateway] final case class Send(
      robotId: Int,
      to: InetSocketAddress,
      bytes: Array[Byte],
      priority: Priority,
      replyTo: Option[ActorRef[Outcome]] = None,
      tag: Long = 0L,
      signed: Boolean = false,
      via: Option[ActorRef[ZeroMqRobotLink.Command]] = None
  ) extends Command {

    /** The size on the wire: the signature field comes on top of a signed frame. */
    def size: Int = if (signed) bytes.length + FrameSigning.FieldBytes else bytes.length
  }

  /** Takes back robot `robotId`'s datagrams marked with `tags` that still wait for the budget: a call superseded by a
    * newer one must not leave after it. A `Send` from the same sender after this one is processed after it.
    */
  private[naogateway] final case class Withdraw(robotId: Int, tags: Set[Long]) extends Command

  /** Robot `robotId` is gone (forgotten): its waiting datagrams and its traffic meter go too. */
  private[naogateway] final case class RobotGone(robotId: Int) extends Command

  /** Counts `datagrams` datagrams of `bytes` in all received from the team, for the two-way traffic figures. */
  private[naogateway] final case class Inbound(datagrams: Int, bytes: Int) extends Command

  /** What the trusted GameController last said (or that it could not be read): the gate decides on it. */
  private[naogateway] final case class GameStateChanged(reading: GameReading) extends Command

  /** Constructors of gate updates. */
  private[naogateway] object GameStateChanged {

    /** A readable packet's state. */
    def apply(state: GameState): GameStateChanged = GameStateChanged(GameReading.Known(state))
  }

  /** Asks for the traffic figures. */
  private[naogateway] final case class GetStats(replyTo: ActorRef[TrafficStats]) extends Command

  /** Sends what the budget allows now (the outbox's own timer sends it; a spec with its own clock too). */
  private[naogateway] case object Drain extends Command
  private case object DrainTimer

  /** Whether a datagram was taken; `tag` is the sender's mark from `Send`. */
  private[naogateway] sealed trait Outcome extends Product with Serializable {
    def tag: Long
  }

  /** Sent, or queued behind the budget. */
  private[naogateway] final case class Accepted(tag: Long) extends Outcome

  /** Not sent because a competition rule forbids it now. */
  private[naogateway] final case class RefusedByRule(tag: Long, rule: String) extends Outcome

  /** Not sent because its class's queue is full. */
  private[naogateway] final case class Dropped(tag: Long, reason: String) extends Outcome

  /** The rule that closes the gate, in words for errors and logs. */
  val NoSendingWhileGameRuns: String = CompetitionGate.NoSendingWhileGameRuns

  private val Second = 1000000000L

  /** An outbox writing to `link` (non-blocking) under `budget`, closing in competition mode while the game runs;
    * `signer` signs the frames sent as `signed`; its decisions (each datagram's outcome, the gate, the budget once a
    * second while sending) go to `tap` while anyone reads it. `clock` (nanoseconds) is what every decision is taken
    * against.
    */
  private[naogateway] def apply(link: DatagramWriter, budget: BudgetSettings, competition: Boolean,
      signer: Option[GatewaySigning] = None, tap: Tap = new Tap,
      clock: () => Long = () => System.nanoTime()): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        new Outbox(link, budget, competition, signer, timers, context.log, tap, clock).behavior()
      }
    }

  /** Whether a game state counts as "the game is running" ([[CompetitionGate.gameRunning]]). */
  def gameRunning(state: GameState): Boolean = CompetitionGate.gameRunning(state)
}

private final class Outbox(
    link: DatagramWriter,
    budget: BudgetSettings,
    competition: Boolean,
    signer: Option[GatewaySigning],
    timers: TimerScheduler[Outbox.Command],
    log: org.slf4j.Logger,
    tap: Tap,
    clock: () => Long
) {
  import Outbox._

  private val out = new TrafficMeter(Second)
  private val in = new TrafficMeter(Second)
  // Keyed by robot id, but only robot actors send, and a forgotten robot's meter goes with it (RobotGone).
  private val perRobot = scala.collection.mutable.Map.empty[Int, TrafficMeter]
  // Heartbeat probes together: however many robots are probed, they take at most budget.probe-share of the budget.
  private val probes = new TrafficMeter(Second)
  private val droppedByClass = Array.fill(Priority.all.size)(0L)
  private var queues: Vector[Queue[Send]] = Vector.fill(Priority.all.size)(Queue.empty)
  private var gameIsRunning = false
  private var reading: GameReading = GameReading.Nothing
  private var refused = 0L
  private var dropped = 0L
  private var lastWarning = Long.MinValue
  private var lastBudgetRecord = clock() - 2 * Second

  /** The outcome of one datagram, and once a second the budget's state, for the tap's readers. */
  private def record(now: Long, s: Send, outcome: String): Unit = if (tap.listening) {
    tap.decision(Decision.Outgoing(s.robotId, s.priority, outcome, s.bytes))
    if (now - lastBudgetRecord >= Second) {
      lastBudgetRecord = now
      tap.decision(Decision.Budget(out.inWindow(now), in.inWindow(now), budget.teamBytesPerSecond,
          Priority.all.map(p => p.name -> queues(p.rank).size).toMap))
    }
  }

  private def robotMeter(robotId: Int) = perRobot.getOrElseUpdate(robotId, new TrafficMeter(Second))

  /** Whether `s` fits the team's and its robot's budget now (what holds back every class behind it). */
  private def fitsBudget(now: Long, s: Send): Boolean =
    s.priority == Priority.Safety || (out.fits(now, s.size, budget.teamBytesPerSecond.toLong) &&
      (budget.robotBytesPerSecond == 0 || robotMeter(s.robotId).fits(now, s.size, budget.robotBytesPerSecond.toLong)))

  /** Whether a probe `s` fits the probes' share (other classes always do). */
  private def fitsShare(now: Long, s: Send): Boolean =
    s.priority != Priority.Heartbeat || probes.fits(now, s.size, budget.probeBytesPerSecond)

  private def allowed(now: Long, s: Send): Boolean = fitsBudget(now, s) && fitsShare(now, s)

  /** The earliest time `s` may go (now, if it may go now). */
  private def fitsAt(now: Long, s: Send): Long = {
    val team = out.fitsAt(now, s.size, budget.teamBytesPerSecond.toLong)
    val robot =
      if (budget.robotBytesPerSecond == 0) now
      else robotMeter(s.robotId).fitsAt(now, s.size, budget.robotBytesPerSecond.toLong)
    val share = if (s.priority == Priority.Heartbeat) probes.fitsAt(now, s.size, budget.probeBytesPerSecond) else now
    math.max(team, math.max(robot, share))
  }

  private def transmit(now: Long, s: Send): Unit = {
    out.record(now, s.size)
    robotMeter(s.robotId).record(now, s.size)
    if (s.priority == Priority.Heartbeat) probes.record(now, s.size)
    // Signed now, not when it was queued: the robot accepts only growing timestamps, and the queues reorder.
    val bytes =
      if (!s.signed) Right(s.bytes)
      else signer.toRight("no signing key").flatMap(_.sign(s.robotId, s.bytes).left.map(_.describe))
    // Written here, on the outbox's own thread: no link actor between the decision and the socket. A full kernel
    // buffer takes nothing (UDP would lose the datagram further on anyway): counted as dropped. A ZeroMQ robot's link
    // reports itself whether its socket took the message. A frame that cannot be signed is never sent unsigned.
    s.via match {
      case Some(zeroMq) => zeroMq ! ZeroMqRobotLink.Send(s.bytes, s.replyTo, s.tag)
      case None =>
        bytes match {
          case Left(why) =>
            dropped += 1
            if (RateLimitedLog.due(dropped)) log.warn("Outbox dropped {} datagram(s) so far: {}", dropped, why)
          case Right(b) if !link.send(b, s.to) =>
            dropped += 1
            if (RateLimitedLog.due(dropped))
              log.warn("Outbox dropped {} datagram(s) so far: the socket did not take one to {}", dropped, s.to)
          // A robot answers every request at once: the port loop looks for the answer before it blocks.
          case Right(_) => PortLoop.answerDue()
        }
    }
    warnIfLoaded(now)
  }

  private def warnIfLoaded(now: Long): Unit = {
    val load = (out.inWindow(now) + in.inWindow(now)).toDouble / budget.teamBytesPerSecond
    if (load >= budget.warnAt && now - lastWarning > 10 * Second) {
      lastWarning = now
      log.warn("Team traffic at {}% of the {} B/s budget", (load * 100).round, budget.teamBytesPerSecond)
    }
  }

  /** Sends what the budget allows, most urgent class first, and sets a timer for the rest. A datagram that does not fit
    * the budget holds back everything behind it; probes held back only by their share let the classes behind them go.
    */
  private def drain(now: Long): Unit = {
    var blocked = false
    var rank = 0
    var waiting = Vector.empty[Send]
    while (rank < queues.size && !blocked) {
      var q = queues(rank)
      var classHeld = false
      while (q.nonEmpty && !blocked && !classHeld) {
        val (s, rest) = q.dequeue
        if (allowed(now, s)) { transmit(now, s); record(now, s, "sent"); q = rest }
        else {
          waiting :+= s
          if (fitsBudget(now, s)) classHeld = true else blocked = true
        }
      }
      queues = queues.updated(rank, q)
      rank += 1
    }
    if (waiting.nonEmpty) {
      val wait = math.max(1000000L, waiting.map(fitsAt(now, _)).min - now)
      timers.startSingleTimer(DrainTimer, Drain, wait.nanos)
    }
  }

  def behavior(): Behavior[Command] = Behaviors.receiveMessage {
    case s: Send =>
      val now = clock()
      if (competition && gameIsRunning) {
        refused += 1
        record(now, s, "refused-by-rule")
        s.replyTo.foreach(_ ! RefusedByRule(s.tag, NoSendingWhileGameRuns))
      } else if (s.signed && !signer.exists(_.canSign(s.robotId)) || s.signed && s.size > WireLimits.MaxDatagramBytes) {
        // Never sent unsigned: without the key, or before the robot's boot epoch is known, the frame is dropped.
        dropped += 1
        record(now, s, "dropped")
        val why = signer match {
          case None => "the frame must be signed, but the gateway has no signing key"
          case Some(g) if !g.canSign(s.robotId) =>
            s"the frame must be signed, but ${SignRefusal.EpochUnknown(s.robotId).describe}"
          case Some(_) => s"signed, the frame would take ${s.size} bytes, more than ${WireLimits.MaxDatagramBytes}"
        }
        if (RateLimitedLog.due(dropped)) log.warn("Outbox dropped {} datagram(s) so far: {}", dropped, why)
        s.replyTo.foreach(_ ! Dropped(s.tag, why))
      } else {
        val rank = s.priority.rank
        if (queues.forall(_.isEmpty) && allowed(now, s)) {
          transmit(now, s)
          record(now, s, "sent")
          s.replyTo.foreach(_ ! Accepted(s.tag))
        } else if (queues(rank).size >= budget.queueCapacity) {
          dropped += 1
          droppedByClass(rank) += 1
          record(now, s, "dropped")
          s.replyTo.foreach(_ ! Dropped(s.tag,
              s"the ${s.priority.name} queue holds ${budget.queueCapacity} datagrams already"))
          // Per class at its 1st, 10th, 100th ... drop: a flood of probes cannot flood the log.
          if (RateLimitedLog.due(droppedByClass(rank)))
            log.warn("Outbox dropped {} datagram(s) so far: {} queue full", droppedByClass(rank), s.priority.name)
        } else {
          queues = queues.updated(rank, queues(rank).enqueue(s))
          record(now, s, "queued")
          s.replyTo.foreach(_ ! Accepted(s.tag))
          // Safety must not wait for the timer; other classes drain when the budget frees, or at once when only probes
          // held back by their share wait (they must not make the others wait for the timer).
          val probesHeld = queues(Priority.Heartbeat.rank).nonEmpty
          if (s.priority == Priority.Safety || !timers.isTimerActive(DrainTimer) || probesHeld) drain(now)
        }
      }
      Behaviors.same
    case Drain =>
      drain(clock())
      Behaviors.same
    case Withdraw(robotId, tags) =>
      if (tap.listening) {
        val now = clock()
        queues.foreach(_.foreach(q => if (q.robotId == robotId && tags(q.tag)) record(now, q, "withdrawn")))
      }
      queues = queues.map(_.filterNot(q => q.robotId == robotId && tags(q.tag)))
      Behaviors.same
    case RobotGone(robotId) =>
      perRobot -= robotId
      queues = queues.map(_.filterNot(_.robotId == robotId))
      Behaviors.same
    case Inbound(datagrams, bytes) =>
      in.record(clock(), bytes, datagrams)
      Behaviors.same
    case GameStateChanged(now) =>
      val nowRunning = CompetitionGate.closes(now)
      if (competition && nowRunning != gameIsRunning) {
        log.info("Competition gate {}: {}", if (nowRunning) "closed" else "open again",
          CompetitionGate.why(now).getOrElse(s"game state $now"))
        if (tap.listening) tap.decision(Decision.Gate(open = !nowRunning, now))
      }
      reading = now
      gameIsRunning = nowRunning
      if (competition && gameIsRunning) {
        // Nothing queued before kick-off may leak out during the game.
        val held = queues.map(_.size).sum
        if (held > 0) log.info("Discarding {} queued datagram(s) at game start", held)
        if (tap.listening) {
          val now = clock()
          queues.foreach(_.foreach(q => record(now, q, "refused-by-rule")))
        }
        queues.foreach(_.foreach(q => q.replyTo.foreach(_ ! RefusedByRule(q.tag, NoSendingWhileGameRuns))))
        refused += held
        queues = Vector.fill(Priority.all.size)(Queue.empty)
      }
      Behaviors.same
    case GetStats(replyTo) =>
      val now = clock()
      replyTo ! TrafficStats(
        out.inWindow(now),
        in.inWindow(now),
        budget.teamBytesPerSecond,
        Priority.all.map(p => p.name -> queues(p.rank).size).toMap,
        out.totalDatagrams,
        in.totalDatagrams,
        refused,
        dropped,
        gameIsRunning,
        competition,
        CompetitionGate.why(reading)
      )
      Behaviors.same
  }
}
