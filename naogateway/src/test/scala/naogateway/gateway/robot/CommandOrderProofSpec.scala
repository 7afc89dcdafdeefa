package naogateway.gateway.robot

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ManualTime, ScalaTestWithActorTestKit, TestProbe}
import akka.actor.typed.scaladsl.Behaviors
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.access.RobotAccess
import naogateway.api.{CallResult, Priority}
import naogateway.gateway.{BudgetSettings, CallSettings}
import naogateway.gateway.robot.RobotStandIn.callActors
import naogateway.gateway.link.UdpLink
import naogateway.wire.{HeaderForm, MessageContents, RpcCall, RpcValue}

/** A walk never leaves after a later stop: not as a retry, not held by the outbox's budget. */
class CommandOrderProofSpec extends ScalaTestWithActorTestKit(ManualTime.config) with AnyWordSpecLike
    with LogCapturing {
  private val manualTime = ManualTime()
  private val settings = CallSettings(2.seconds, idempotentRetries = 2, stashCapacity = 8)
  private val walk = RpcCall("motion", "walk", Vector.fill(3)(RpcValue.Number(0.2f)))
  private val stop = RpcCall("motion", "stop", Vector.empty)

  /** Everything the probe gets until it has been quiet for 300 ms. */
  private def drain[T](p: TestProbe[T]): Vector[T] = {
    var acc = Vector.empty[T]
    var more = true
    while (more)
      try acc :+= p.receiveMessage(300.millis)
      catch { case _: AssertionError => more = false }
    acc
  }

  /** A writer that hands every datagram to `link` as the send it is, and always takes it. */
  private def writer(link: akka.actor.typed.ActorRef[UdpLink.Command]): naogateway.transport.DatagramWriter =
    (bytes, to) => {
      link ! UdpLink.Send(bytes, to)
      true
    }

  "A walk" must {
    "never be retried after a later stop" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val outbox = createTestProbe[Outbox.Command]()
      val caller = createTestProbe[CallResult]()
      val (responder, _) = callActors(testKit, 3, settings, robot, outbox)
      responder ! RobotAccess.Call(walk, caller.ref)
      responder ! RobotAccess.Call(stop, caller.ref, Priority.Safety)
      manualTime.timePasses(2.seconds)
      val names = drain(outbox).collect { case s: Outbox.Send => RobotStandIn.callIn(s).name }
      names.head shouldBe "motion.walk"
      names.tail should not be empty
      names.tail should not contain "motion.walk"
    }
    "never leave the outbox after a later stop when the budget held it" in {
      val link = createTestProbe[UdpLink.Command]()
      val outbox = spawn(Outbox(writer(link.ref), BudgetSettings(1400, 0, 1.0), competition = false))
      val robot = spawn(Behaviors.receiveMessage[RobotActor.FromChild] {
        case RobotActor.ReachabilityWanted(r) => r ! true; Behaviors.same
        case _                                => Behaviors.same
      })
      // The budget is spent: the walk waits in the outbox.
      outbox ! Outbox.Send(3, RobotStandIn.RobotAddress, new Array[Byte](1390), Priority.Command)
      link.receiveMessage()
      val caller = createTestProbe[CallResult]()
      val sender = spawn(NoResponseActor(3, settings, robot))
      val responder = spawn(ResponseActor(3, settings, robot, sender, online = true))
      sender ! NoResponseActor.RouteChanged(RobotFrames.Route.Datagrams(outbox, RobotStandIn.RobotAddress,
          HeaderForm.Legacy))
      responder ! RobotAccess.Call(walk, caller.ref)
      responder ! RobotAccess.Call(stop, caller.ref, Priority.Safety)
      def name(m: UdpLink.Command): String = m match {
        case UdpLink.Send(b, _) =>
          MessageContents.decodeFrame(b).toOption.flatMap(_._2.rpcRequest).map(RpcCall.fromProto(_).name).getOrElse("?")
        case _ => "?"
      }
      name(link.receiveMessage(3.seconds)) shouldBe "motion.stop"
      // The budget frees after a second of real time (the meter reads the clock); the drain timer is manual.
      Thread.sleep(1200)
      manualTime.timePasses(2.seconds)
      drain(link).map(name) should not contain "motion.walk"
    }
  }
}
