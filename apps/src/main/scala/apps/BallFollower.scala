package apps

import naogateway.wire.ActuatorGroup

import scala.concurrent.duration._
import scala.util.{Failure, Success}

import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.{ActorRef, Behavior}
import akka.stream.scaladsl.{Keep, Sink}
import akka.stream.{KillSwitches, UniqueKillSwitch}

import naogateway.api.VisionFrame
import naogateway.wire.Posture
import robotmiddleware.{AppEvent, RobotInterface}

/** The ball follower app: tracks the ball with the head from HaViMo2 regions and walks to it. Standing at the ball it
  * takes a look every [[LookInterval]] ([[LookFrames]] frames) instead of watching every frame: the camera's frames
  * cross the robot's WiFi, the gateway and the cluster for nothing while the ball lies still.
  */
object BallFollower {

  /** What the follower accepts. */
  sealed trait Command

  /** Answers whether the ball has been reached. */
  final case class GetProgress(replyTo: ActorRef[Progress]) extends Command

  private final case class Frame(frame: VisionFrame.Regions) extends Command
  private final case class Leased(result: scala.util.Try[akka.Done]) extends Command
  private final case class Stood(result: scala.util.Try[Posture]) extends Command
  private final case class WalkDone(result: scala.util.Try[akka.Done]) extends Command
  private final case class Preempted(event: AppEvent) extends Command
  private case object Retry extends Command
  private case object Look extends Command

  /** Head targets closer than this (radians) to the last one sent are not sent again. */
  val HeadDeadband: Double = 0.01

  /** Standing at the ball, the follower watches this many frames, then turns the camera off until the next look. */
  val LookFrames: Int = 4

  /** Standing at the ball, the pause between two looks. */
  val LookInterval: FiniteDuration = 2.seconds

  /** The camera's stream while it runs (its switch ends it, and with it the watch at the middleware), and the frames
    * seen in a row at the ball.
    */
  private final case class Camera(switch: Option[UniqueKillSwitch], framesAtBall: Int)

  /** How far the follower is. */
  final case class Progress(reached: Boolean, lastDistance: Option[Double], frames: Long)

  /** A follower steering robot `robotId` through `robot`. */
  def apply(robot: RobotInterface, robotId: Int): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withTimers { timers =>
        implicit val system: akka.actor.typed.ActorSystem[_] = context.system

        def acquire(): Unit =
          context.pipeToSelf(robot.acquire(robotId, ActuatorGroup.Walk, ActuatorGroup.Head))(Leased.apply)

        // The streams run on other threads: they may only use the ref, never the context.
        val self = context.self

        def watch(): Camera =
          Camera(Some(robot.vision(robotId).collect { case r: VisionFrame.Regions => Frame(r) }
                .viaMat(KillSwitches.single)(Keep.right).to(Sink.foreach(self ! _)).run()),
            0)

        // The camera on, as every state but a rest at the ball wants it.
        def on(camera: Camera): Camera = if (camera.switch.isDefined) camera else watch()

        def following(state: BallFollowerControl.State, progress: Progress, lastWalk: (Double, Double),
            lastHead: (Double, Double) = (Double.NaN, Double.NaN), camera: Camera): Behavior[Command] =
          Behaviors.receiveMessage {
            case Frame(frame) =>
              val (next, t) = BallFollowerControl.step(state, frame.regions)
              // A head that already looks where it should gets no command: at 16 frames a second, a still ball
              // would otherwise cost a datagram to the robot per frame.
              val head =
                if (math.abs(t.pan - lastHead._1) > HeadDeadband || math.abs(
                    t.tilt - lastHead._2) > HeadDeadband || lastHead._1.isNaN) {
                  robot.head(robotId, t.pan, t.tilt)
                  (t.pan, t.tilt)
                } else lastHead
              // Only changed velocities go out; the middleware keeps the current walk alive.
              val walk = (t.vx, t.omega)
              val changed = math.abs(walk._1 - lastWalk._1) > 0.02 || math.abs(walk._2 - lastWalk._2) > 0.05
              if (changed || lastWalk._1.isNaN) {
                val sent = if (walk == ((0.0, 0.0))) robot.stop(robotId) else robot.walk(robotId, t.vx, 0.0, t.omega)
                context.pipeToSelf(sent)(WalkDone.apply)
              }
              if (next.reached && !state.reached) context.log.info("Robot [{}] reached the ball", robotId)
              // At the ball, seeing it and standing: after a look's frames the camera rests until the next look.
              val atBall =
                if (next.reached && t.ballDistance.isDefined && walk == ((0.0, 0.0))) camera.framesAtBall + 1 else 0
              val nextCamera =
                if (atBall < LookFrames || camera.switch.isEmpty) camera.copy(framesAtBall = atBall)
                else {
                  camera.switch.foreach(_.shutdown())
                  timers.startSingleTimer(Look, LookInterval)
                  Camera(None, 0)
                }
              following(next, Progress(next.reached, t.ballDistance.orElse(progress.lastDistance), progress.frames + 1),
                walk, head, nextCamera)
            case Look =>
              following(state, progress, lastWalk, lastHead, on(camera))
            case WalkDone(Failure(e)) =>
              // The robot refused or missed it: send the current target again with the next frame.
              context.log.debug("Ball follower walk on robot [{}] failed: {}", robotId, e.getMessage)
              following(state, progress, (Double.NaN, Double.NaN), (Double.NaN, Double.NaN), camera)
            case GetProgress(replyTo) =>
              replyTo ! progress
              Behaviors.same
            case Preempted(event) =>
              context.log.info("Ball follower on robot [{}]: {}", robotId, event)
              timers.cancel(Look)
              timers.startSingleTimer(Retry, 2.seconds)
              waiting(progress, on(camera))
            case Leased(_) | Retry | Stood(_) | WalkDone(_) => Behaviors.same
          }

        def standingUp(progress: Progress, camera: Camera): Behavior[Command] = Behaviors.receiveMessage {
          case Stood(Success(_)) =>
            context.log.info("Ball follower has robot [{}] standing", robotId)
            following(BallFollowerControl.initial, progress, (Double.NaN, Double.NaN), camera = camera)
          case Stood(Failure(e)) =>
            context.log.info("Robot [{}] did not stand up: {}; trying again", robotId, e.getMessage)
            timers.startSingleTimer(Retry, 1.second)
            Behaviors.same
          case Retry =>
            context.pipeToSelf(robot.posture(robotId, Posture.Stand))(Stood.apply)
            Behaviors.same
          case GetProgress(replyTo) =>
            replyTo ! progress
            Behaviors.same
          case Preempted(_) =>
            timers.startSingleTimer(Retry, 2.seconds)
            waiting(progress, camera)
          case Frame(_) | Leased(_) | WalkDone(_) | Look => Behaviors.same
        }

        def waiting(progress: Progress, camera: Camera): Behavior[Command] = Behaviors.receiveMessage {
          case Retry =>
            acquire()
            Behaviors.same
          case Leased(Success(_)) =>
            context.log.info("Ball follower has robot [{}]", robotId)
            context.pipeToSelf(robot.posture(robotId, Posture.Stand))(Stood.apply)
            standingUp(progress, camera)
          case Leased(Failure(e)) =>
            context.log.info("Ball follower waits for robot [{}]: {}", robotId, e.getMessage)
            timers.startSingleTimer(Retry, 2.seconds)
            Behaviors.same
          case GetProgress(replyTo) =>
            replyTo ! progress
            Behaviors.same
          case Frame(_) | Preempted(_) | Stood(_) | WalkDone(_) | Look => Behaviors.same
        }

        robot.appEvents.runWith(Sink.foreach(e => self ! Preempted(e)))
        acquire()
        waiting(Progress(reached = false, None, 0), watch())
      }
    }
}
