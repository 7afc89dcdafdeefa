package naogateway.gateway.robot

import java.net.{InetAddress, InetSocketAddress}

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ManualTime, ScalaTestWithActorTestKit, TestProbe}
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.api.{GatewayEvent, RobotOnline}
import naogateway.gateway.GatewaySettings
import naogateway.proto.{
  DebuggingCommands,
  DebuggingOption,
  DebuggingOptionList,
  DebuggingOptionNames,
  RobotHealth,
  Status
}
import naogateway.wire.{HeaderForm, MessageContents}

/** protocol.md 8: the gateway pulls a robot's option list first and enables options only once it has the answer. */
class OptionPullSpec extends ScalaTestWithActorTestKit(ManualTime.config) with AnyWordSpecLike with LogCapturing {
  private val manualTime = ManualTime()
  private val settings = GatewaySettings(system)
  private val address = new InetSocketAddress(InetAddress.getLoopbackAddress, 3838)

  private val pull = DebuggingCommands(optionPull = Some(true))
  private def enable(names: String*) = DebuggingCommands(optionEnable = Some(DebuggingOptionNames(names)))
  private def push(names: String*) =
    DebuggingCommands(optionPush = Some(DebuggingOptionList(names.map(n => DebuggingOption(name = n)))))

  private def debugOf(m: Outbox.Command): Option[DebuggingCommands] = m match {
    case s: Outbox.Send => MessageContents.decodeFrame(s.bytes).toOption.flatMap(_._2.debuggingCommands)
    case _              => None
  }

  /** The next option command sent (the heartbeat's probes skipped). */
  private def nextDebug(outbox: TestProbe[Outbox.Command]): DebuggingCommands = {
    var found: Option[DebuggingCommands] = None
    while (found.isEmpty) found = debugOf(outbox.receiveMessage(10.seconds))
    found.get
  }

  /** Every option command sent until the outbox has been quiet for a moment. */
  private def remainingDebug(outbox: TestProbe[Outbox.Command]): Vector[DebuggingCommands] =
    Iterator.continually(scala.util.Try(outbox.receiveMessage(300.millis)).toOption)
      .takeWhile(_.isDefined).flatten.flatMap(debugOf).toVector

  private def keepAlive(robot: akka.actor.typed.ActorRef[RobotActor.Command], boot: Int): Unit =
    robot ! RobotActor.FrameReceived(
      MessageContents(6, status = Some(Status(teamID = Some(1))),
        robotHealth = Some(RobotHealth(uptimeMs = Some(1000), bootId = Some(boot)))),
      HeaderForm.Legacy, 60)

  /** Lets `d` pass in manual time while the robot keeps sending keep-alives, so it stays online. */
  private def passWhileAlive(robot: akka.actor.typed.ActorRef[RobotActor.Command], boot: Int, d: FiniteDuration): Unit =
    (1 to (d / 200.millis).toInt).foreach { _ =>
      keepAlive(robot, boot)
      manualTime.timePasses(200.millis)
    }

  "A robot actor" must {
    "send optionPull first, repeat it every second until the push, then enable only what the robot offers" in {
      val outbox = createTestProbe[Outbox.Command]()
      val events = createTestProbe[GatewayEvent]()
      val robot = spawn(RobotActor(6, address, settings, outbox.ref, RobotWiring.to(events.ref), heard = true))
      events.expectMessageType[RobotOnline]
      keepAlive(robot, boot = 1)
      // A camera subscriber wants an option before the list is known: it waits for the push.
      robot ! RobotActor.OptionCommand(enable("havimo.regions", "no.such"))
      nextDebug(outbox) shouldBe pull
      remainingDebug(outbox) shouldBe empty
      passWhileAlive(robot, boot = 1, 1.second)
      nextDebug(outbox) shouldBe pull
      robot ! RobotActor.FrameReceived(MessageContents(6,
          debuggingCommands = Some(push("status.text", "havimo.regions", "havimo.grid"))),
        HeaderForm.Legacy, 80)
      nextDebug(outbox) shouldBe enable("havimo.regions")
      // The list is known: no more pulls, and later commands go out at once.
      passWhileAlive(robot, boot = 1, 3.seconds)
      remainingDebug(outbox) shouldBe empty
      robot ! RobotActor.OptionCommand(enable("status"))
      nextDebug(outbox) shouldBe enable("status")
    }

    "pull the list again after a restart and re-enable the active options once it arrives" in {
      val outbox = createTestProbe[Outbox.Command]()
      val events = createTestProbe[GatewayEvent]()
      val robot = spawn(RobotActor(6, address, settings, outbox.ref, RobotWiring.to(events.ref), heard = true))
      keepAlive(robot, boot = 1)
      nextDebug(outbox) shouldBe pull
      robot ! RobotActor.FrameReceived(MessageContents(6, debuggingCommands = Some(push("havimo.regions"))),
        HeaderForm.Legacy, 40)
      robot ! RobotActor.OptionCommand(enable("havimo.regions"))
      nextDebug(outbox) shouldBe enable("havimo.regions")
      // A new session: three keep-alives in a row of it (new-session.keep-alives), then its list first, nothing enabled
      // before it arrives.
      (1 to settings.newSessionKeepAlives).foreach(_ => keepAlive(robot, boot = 2))
      nextDebug(outbox) shouldBe pull
      remainingDebug(outbox) shouldBe empty
      robot ! RobotActor.FrameReceived(MessageContents(6, debuggingCommands = Some(push("havimo.regions"))),
        HeaderForm.Legacy, 40)
      nextDebug(outbox) shouldBe enable("havimo.regions")
    }
  }
}
