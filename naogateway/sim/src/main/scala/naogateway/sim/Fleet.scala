package naogateway.sim

import java.net.{InetAddress, InetSocketAddress}
import java.util.concurrent.atomic.AtomicLong

import scala.concurrent.{Future, Promise}
import scala.concurrent.duration._
import scala.util.{Failure, Success, Try}

import akka.Done
import akka.actor.typed.scaladsl.AskPattern._
import akka.actor.typed.scaladsl.{ActorContext, Behaviors, StashBuffer}
import akka.actor.typed.{ActorRef, ActorSystem, Behavior}
import akka.pattern.StatusReply
import akka.util.Timeout

import naogateway.wire.stream.StreamSettings

/** One robot of a fleet: its id, where it receives (its own IP at the receive port), and its actor. */
final case class FleetRobot(robotId: Int, address: InetSocketAddress, robot: ActorRef[SimulatedRobot.Command])

/** Settings of a fleet of simulated robots of one team, all sending to one gateway.
  *
  * @param gateway
  *   the gateway's robot port, where every robot sends keep-alives and debug output
  * @param robotIds
  *   distinct robot ids; the first robot is the keeper
  * @param faithfulLink
  *   each robot's datagrams pass the GS1500M and CM-530 models; switch off for hundreds of robots
  * @param firstAddress
  *   the IP address of the fleet's first robot; the `i`-th robot has `firstAddress + i`, so every robot is a host of
  *   its own (on loopback: Linux routes all of 127.0.0.0/8), as a team's robots are
  * @param receivePort
  *   where each robot receives on its own address (3838, docs/protocol.md section 2); each sends from a port the
  *   operating system picks
  * @param spreadKeepAlives
  *   spread the robots' keep-alive phases over one interval, as real robots switched on one by one would be, instead of
  *   every robot sending in the same instant
  * @param customize
  *   a last change to each robot's settings (debug timings, battery, stream hook, …)
  */
final case class FleetSettings(
    gateway: InetSocketAddress,
    robotIds: Vector[Int] = (1 to 5).toVector,
    teamId: Int = 1,
    faithfulLink: Boolean = true,
    timeScale: Double = SimulatedRobotSettings.DefaultTimeScale,
    firstAddress: InetAddress = FleetSettings.DemoFirstAddress,
    receivePort: Int = SimulatedRobot.ReceivePort,
    seed: Long = 1L,
    spreadKeepAlives: Boolean = true,
    startTimeout: FiniteDuration = 30.seconds,
    askTimeout: FiniteDuration = 5.seconds,
    stopTimeout: FiniteDuration = 30.seconds,
    customize: SimulatedRobotSettings => SimulatedRobotSettings = identity
) {
  require(robotIds.nonEmpty, "a fleet needs at least one robot")
  require(robotIds.distinct.size == robotIds.size, s"robot ids must be distinct: ${robotIds.diff(robotIds.distinct)}")
  require(robotIds.forall(_ >= 0), "robot ids must not be negative")
  require(firstAddress.getAddress.length == 4, s"firstAddress $firstAddress is not an IPv4 address")

  /** The IP address of the fleet's `index`-th robot: `firstAddress + index`. */
  def addressOf(index: Int): InetAddress = {
    val first = java.nio.ByteBuffer.wrap(firstAddress.getAddress).getInt
    InetAddress.getByAddress(java.nio.ByteBuffer.allocate(4).putInt(first + index).array())
  }

  /** These settings with every robot taking part in the secure stream (see [[SimulatedRobotSettings.withStream]]),
    * after whatever `customize` already does.
    */
  def withStream(settings: StreamSettings = StreamSettings.thesis): FleetSettings =
    copy(customize = customize.andThen(_.withStream(settings)))
}

/** Shorthands for [[FleetSettings]]. */
object FleetSettings {

  /** The demo's first robot address, 127.0.0.11: robots 127.0.0.11, .12, ... stay clear of 127.0.0.1, where the gateway
    * listens.
    */
  val DemoFirstAddress: InetAddress = InetAddress.getByAddress(Array[Byte](127, 0, 0, 11))

  /** Robots 1 to `n`. */
  def ofSize(n: Int, gateway: InetSocketAddress): FleetSettings = {
    require(n > 0, s"a fleet needs at least one robot, got $n")
    FleetSettings(gateway, (1 to n).toVector)
  }
}

/** A fleet of [[SimulatedRobot]]s: starts them with distinct ids, roles and start poses, knows their addresses,
  * power-cycles one on request and stops them all, each socket closed.
  *
  * Use the behavior under a launcher's guardian, or [[Fleet.start]] for a [[FleetHandle]] from tests and tools. A robot
  * that fails to bind fails the whole start: the fleet then stops the robots it has and itself.
  */
object Fleet {

  /** What a fleet accepts. */
  sealed trait Command

  /** Every robot with its address, once all are bound (an error if the fleet could not start). */
  final case class GetRobots(replyTo: ActorRef[StatusReply[Vector[FleetRobot]]]) extends Command

  /** Power-cycles one robot; the reply comes once it has fallen silent. */
  final case class PowerCycle(robotId: Int, bootDelay: FiniteDuration, replyTo: ActorRef[StatusReply[Done]])
      extends Command

  /** A snapshot of one robot. */
  final case class GetState(robotId: Int, replyTo: ActorRef[StatusReply[RobotView]]) extends Command

  /** Stops every robot and then the fleet; `Done` once every socket is closed. */
  final case class Stop(replyTo: ActorRef[Done]) extends Command

  private final case class RobotStarted(result: SimulatedRobot.StartResult) extends Command
  private final case class RobotStopped(robotId: Int) extends Command
  private final case class PoweredOff(result: Try[RobotView], replyTo: ActorRef[StatusReply[Done]]) extends Command
  private final case class StateAnswered(result: Try[RobotView], replyTo: ActorRef[StatusReply[RobotView]])
      extends Command

  /** Roles after the keeper, in turn. */
  val FieldRoles: Vector[String] = Vector("striker", "defender", "supporter")

  /** The GameController knows 11 player slots per team; player numbers repeat beyond that. */
  val PlayerSlots: Int = 11

  private val StashCapacity = 10000
  private val fleetNames = new AtomicLong()

  /** The role of the fleet's `index`-th robot: the first keeps goal, the others take the field roles in turn. */
  def role(index: Int): String = if (index == 0) "keeper" else FieldRoles((index - 1) % FieldRoles.size)

  /** Where the `index`-th of `count` robots starts: the keeper in front of its own goal, the others on a grid over the
    * own half, all facing the opponent's goal.
    */
  def startPose(index: Int, count: Int): Pose =
    if (index == 0) Pose(-4.2, 0.0, 0.0)
    else {
      val others = math.max(1, count - 1)
      val columns = math.max(1, math.ceil(math.sqrt(others.toDouble)).toInt)
      val rows = (others + columns - 1) / columns
      val (column, row) = ((index - 1) % columns, (index - 1) / columns)
      val x = if (columns == 1) -2.0 else -3.5 + 3.0 * column / (columns - 1)
      val y = if (rows == 1) 0.0 else -2.5 + 5.0 * row / (rows - 1)
      Pose(x, y, 0.0)
    }

  /** The settings of every robot of the fleet, in the order of `settings.robotIds`. */
  def robotSettings(settings: FleetSettings): Vector[SimulatedRobotSettings] = {
    val count = settings.robotIds.size
    settings.robotIds.zipWithIndex.map { case (id, index) =>
      val firmware = FirmwareSettings(
        robotId = id,
        teamId = settings.teamId,
        playerNumber = index % PlayerSlots + 1,
        role = role(index),
        startPose = startPose(index, count)
      )
      val phase =
        if (settings.spreadKeepAlives) firmware.keepAliveInterval * index.toLong / count.toLong else Duration.Zero
      settings.customize(
        SimulatedRobotSettings(
          firmware = firmware,
          gateway = settings.gateway,
          bindAddress = new InetSocketAddress(settings.addressOf(index), 0),
          receivePort = settings.receivePort,
          faithfulLink = settings.faithfulLink,
          timeScale = settings.timeScale,
          seed = settings.seed * 1000003L + id,
          keepAlivePhase = phase
        )
      )
    }
  }

  /** A fleet with `settings`; its robots start at once, and `reportTo` learns whether they all did. */
  def apply(
      settings: FleetSettings, reportTo: Option[ActorRef[StatusReply[Vector[FleetRobot]]]] = None): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withStash(StashCapacity) { stash =>
        val started = context.messageAdapter[SimulatedRobot.StartResult](RobotStarted.apply)
        val robots = robotSettings(settings).map { s =>
          val id = s.firmware.robotId
          val robot = context.spawn(SimulatedRobot(s, Some(started)), s"robot-$id")
          context.watchWith(robot, RobotStopped(id))
          id -> robot
        }
        new Fleet(settings, context, stash, robots, reportTo).starting(Map.empty)
      }
    }

  /** Starts a fleet as a system actor; the handle comes once every robot is bound, or the reason it failed. */
  def start(system: ActorSystem[_], settings: FleetSettings): Future[FleetHandle] = {
    val outcome = Promise[Vector[FleetRobot]]()
    val n = fleetNames.incrementAndGet()
    // The reporter exists before the fleet, so a start that fails at once cannot lose its reason.
    val reporter = system.systemActorOf(
      Behaviors.receiveMessage[StatusReply[Vector[FleetRobot]]] { reply =>
        outcome.tryComplete(if (reply.isSuccess) Success(reply.getValue) else Failure(reply.getError))
        Behaviors.stopped
      },
      s"simulated-fleet-$n-start"
    )
    val fleet = system.systemActorOf(Fleet(settings, Some(reporter)), s"simulated-fleet-$n")
    val timer = akka.pattern.after(settings.startTimeout)(
      Future.failed[Vector[FleetRobot]](
        new java.util.concurrent.TimeoutException(s"fleet did not start within ${settings.startTimeout}"))
    )(system)
    Future
      .firstCompletedOf(Seq(outcome.future, timer))(system.executionContext)
      .transform {
        case Success(members) => Success(new FleetHandle(fleet, members, settings)(system))
        case Failure(e)       =>
          // A fleet that failed stops by itself; one that timed out must be told, so no socket stays open.
          fleet ! Stop(system.ignoreRef)
          Failure(e)
      }(system.executionContext)
  }
}

private final class Fleet(
    settings: FleetSettings,
    context: ActorContext[Fleet.Command],
    stash: StashBuffer[Fleet.Command],
    robots: Vector[(Int, ActorRef[SimulatedRobot.Command])],
    reportTo: Option[ActorRef[StatusReply[Vector[FleetRobot]]]]
) {
  import Fleet._

  private implicit val askTimeout: Timeout = Timeout(settings.askTimeout)
  private val order: Map[Int, Int] = robots.map(_._1).zipWithIndex.toMap

  def starting(bound: Map[Int, FleetRobot]): Behavior[Command] =
    Behaviors.receiveMessage {
      case RobotStarted(SimulatedRobot.Started(id, robot, address)) =>
        val next = bound.updated(id, FleetRobot(id, address, robot))
        if (next.size < robots.size) starting(next)
        else {
          val members = next.values.toVector.sortBy(m => order(m.robotId))
          context.log.info("Fleet of {} simulated robots of team {} is up, sending to {}", members.size,
            settings.teamId,
            settings.gateway)
          reportTo.foreach(_ ! StatusReply.Success(members))
          stash.unstashAll(running(members))
        }
      case RobotStarted(SimulatedRobot.StartFailed(id, reason)) =>
        failed(s"robot $id could not start: $reason", robots.map(_._1).toSet - id)
      case RobotStopped(id) =>
        failed(s"robot $id stopped while the fleet started", robots.map(_._1).toSet - id)
      case other =>
        if (stash.isFull) context.log.warn("Fleet dropped {} while starting", other)
        else stash.stash(other)
        Behaviors.same
    }

  private def failed(reason: String, alive: Set[Int]): Behavior[Command] = {
    context.log.warn("Fleet cannot start: {}", reason)
    val error = StatusReply.Error[Nothing](reason)
    reportTo.foreach(_ ! error)
    val waiting = Vector.newBuilder[ActorRef[Done]]
    stash.foreach {
      case GetRobots(replyTo)        => replyTo ! error
      case PowerCycle(_, _, replyTo) => replyTo ! error
      case GetState(_, replyTo)      => replyTo ! error
      case Stop(replyTo)             => waiting += replyTo
      case _                         => ()
    }
    stash.clear()
    stopping(alive, waiting.result(), Some(reason))
  }

  private def running(members: Vector[FleetRobot]): Behavior[Command] = {
    val byId = members.map(m => m.robotId -> m).toMap
    def withRobot[A](id: Int, replyTo: ActorRef[StatusReply[A]])(f: FleetRobot => Unit): Behavior[Command] = {
      byId.get(id) match {
        case Some(member) => f(member)
        case None         => replyTo ! StatusReply.Error(s"no robot $id in this fleet")
      }
      Behaviors.same
    }
    Behaviors.receiveMessage {
      case GetRobots(replyTo) =>
        replyTo ! StatusReply.Success(members)
        Behaviors.same
      case PowerCycle(id, bootDelay, replyTo) =>
        withRobot(id, replyTo) { member =>
          member.robot ! SimulatedRobot.PowerCycle(bootDelay)
          // Sent after the power cycle by the same sender, so the snapshot shows the robot already silent.
          context.ask(member.robot, SimulatedRobot.GetState.apply)(PoweredOff(_, replyTo))
        }
      case PoweredOff(Success(_), replyTo) =>
        replyTo ! StatusReply.Ack
        Behaviors.same
      case PoweredOff(Failure(e), replyTo) =>
        replyTo ! StatusReply.Error(e)
        Behaviors.same
      case GetState(id, replyTo) =>
        withRobot(id, replyTo)(member =>
          context.ask(member.robot, SimulatedRobot.GetState.apply)(StateAnswered(_, replyTo)))
      case StateAnswered(result, replyTo) =>
        replyTo ! result.fold(StatusReply.Error(_), StatusReply.Success(_))
        Behaviors.same
      case RobotStopped(id) =>
        context.log.warn("Simulated robot [{}] stopped on its own; the fleet goes on without it", id)
        running(members.filterNot(_.robotId == id))
      case Stop(replyTo) =>
        context.log.info("Fleet of {} simulated robots stops", members.size)
        stopping(members.map(_.robotId).toSet, Vector(replyTo), None)
      case RobotStarted(_) =>
        Behaviors.same
    }
  }

  private def stopping(alive: Set[Int], waiting: Vector[ActorRef[Done]], failure: Option[String]): Behavior[Command] = {
    robots.filter { case (id, _) => alive(id) }.foreach { case (_, robot) =>
      robot ! SimulatedRobot.Stop(context.system.ignoreRef)
    }
    awaitStopped(alive, waiting, failure)
  }

  private def awaitStopped(
      alive: Set[Int], waiting: Vector[ActorRef[Done]], failure: Option[String]): Behavior[Command] =
    if (alive.isEmpty) {
      waiting.foreach(_ ! Done)
      Behaviors.stopped
    } else {
      val refusal = s"the fleet is stopping${failure.fold("")(r => s" ($r)")}"
      Behaviors.receiveMessage {
        case RobotStopped(id)          => awaitStopped(alive - id, waiting, failure)
        case Stop(replyTo)             => awaitStopped(alive, waiting :+ replyTo, failure)
        case GetRobots(replyTo)        => replyTo ! StatusReply.Error(failure.getOrElse(refusal)); Behaviors.same
        case PowerCycle(_, _, replyTo) => replyTo ! StatusReply.Error(refusal); Behaviors.same
        case GetState(_, replyTo)      => replyTo ! StatusReply.Error(refusal); Behaviors.same
        case PoweredOff(_, replyTo)    => replyTo ! StatusReply.Error(refusal); Behaviors.same
        case StateAnswered(_, replyTo) => replyTo ! StatusReply.Error(refusal); Behaviors.same
        case RobotStarted(_)           => Behaviors.same
      }
    }
}

/** A started fleet, for tests and launchers: the robots' addresses, and futures for what the fleet does. */
final class FleetHandle private[sim] (val fleet: ActorRef[Fleet.Command], val members: Vector[FleetRobot],
    settings: FleetSettings)(
    implicit system: ActorSystem[_]
) {
  private implicit val timeout: Timeout = Timeout(settings.askTimeout)

  /** Every robot's id and the address it receives at, in the order of the settings. */
  def robots: Vector[(Int, InetSocketAddress)] = members.map(m => m.robotId -> m.address)

  /** Where robot `robotId` receives. */
  def address(robotId: Int): Option[InetSocketAddress] = members.find(_.robotId == robotId).map(_.address)

  /** The actor of robot `robotId`, for commands the fleet does not pass on (battery, ball). */
  def robot(robotId: Int): Option[ActorRef[SimulatedRobot.Command]] = members.find(_.robotId == robotId).map(_.robot)

  /** Power-cycles robot `robotId`; completes once it has fallen silent. */
  def powerCycle(robotId: Int, bootDelay: FiniteDuration = SimulatedRobot.ModuleBootDelay): Future[Done] =
    fleet.askWithStatus[Done](Fleet.PowerCycle(robotId, bootDelay, _))

  /** A snapshot of robot `robotId`. */
  def state(robotId: Int): Future[RobotView] = fleet.askWithStatus[RobotView](Fleet.GetState(robotId, _))

  /** Stops every robot and the fleet; completes once every socket is closed. */
  def stop(): Future[Done] = fleet.ask[Done](Fleet.Stop(_))(Timeout(settings.stopTimeout), system.scheduler)
}
