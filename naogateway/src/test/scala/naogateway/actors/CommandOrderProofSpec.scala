package naogateway.actors

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ManualTime, ScalaTestWithActorTestKit, TestProbe}
import akka.actor.typed.scaladsl.Behaviors
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway._
import naogateway.actors.RobotStandIn.reachable
import naogateway.link.UdpLink
import naogateway.proto.Request
import naogateway.wire.{RpcCall, RpcValue}

/** Whether a walk can leave after a stop (old API form). */
class CommandOrderProofSpec extends ScalaTestWithActorTestKit(ManualTime.config) with AnyWordSpecLike with LogCapturing {
  private val manualTime = ManualTime()
  private val settings = CallSettings(2.seconds, idempotentRetries = 2, stashCapacity = 8)
  private val walk = RpcCall("motion", "walk", Vector.fill(3)(RpcValue.Number(0.2f)))
  private val stop = RpcCall("motion", "stop", Vector.empty)

  private def drain[T](p: TestProbe[T]): Vector[T] = {
    var acc = Vector.empty[T]
    var more = true
    while (more) try acc :+= p.receiveMessage(300.millis) catch { case _: AssertionError => more = false }
    acc
  }

  "A walk" must {
    "never be retried after a later stop" in {
      val robot = createTestProbe[RobotActor.FromChild]()
      val caller = createTestProbe[CallResult]()
      val responder = spawn(ResponseActor(3, settings, robot.ref, online = true))
      reachable(robot)
      responder ! ResponseActor.Call(walk, caller.ref)
      responder ! ResponseActor.Call(stop, caller.ref, Priority.Safety)
      manualTime.timePasses(2.seconds)
      val names = robot.receiveMessages(2).collect { case RobotActor.Transmit(RobotActor.Outbound.CallOut(c), _, _, _) => c.name }
      names shouldBe Vector("motion.walk", "motion.stop")
      drain(robot).collect { case RobotActor.Transmit(RobotActor.Outbound.CallOut(c), _, _, _) => c.name } should not contain "motion.walk"
    }
    "never leave the outbox after a later stop when the budget held it" in {
      val link = createTestProbe[UdpLink.Command]()
      val outbox = spawn(Outbox(link.ref, BudgetSettings(1400, 0, 1.0), competition = false))
      val to = new InetSocketAddress("127.0.0.1", 1)
      // The old path: the robot actor turns a child's Transmit into an outbox Send.
      val robot = spawn(Behaviors.receiveMessage[RobotActor.FromChild] {
        case RobotActor.Transmit(RobotActor.Outbound.CallOut(c), p, o, tag) =>
          outbox ! Outbox.Send(3, to, c.toProto.toByteArray, p, o, tag); Behaviors.same
        case RobotActor.ReachabilityWanted(r) => r ! true; Behaviors.same
        case _ => Behaviors.same
      })
      outbox ! Outbox.Send(3, to, new Array[Byte](1390), Priority.Command)
      link.receiveMessage()
      val caller = createTestProbe[CallResult]()
      val responder = spawn(ResponseActor(3, settings, robot, online = true))
      responder ! ResponseActor.Call(walk, caller.ref)
      responder ! ResponseActor.Call(stop, caller.ref, Priority.Safety)
      def name(m: UdpLink.Command): String = m match {
        case UdpLink.Send(b, _) => RpcCall.fromProto(Request.parseFrom(b)).name
        case _                  => "?"
      }
      name(link.receiveMessage()) shouldBe "motion.stop"
      // The budget frees after a second of real time (the meter reads the clock); the drain timer is manual.
      Thread.sleep(1200)
      manualTime.timePasses(2.seconds)
      drain(link).map(name) should not contain "motion.walk"
    }
  }
}
