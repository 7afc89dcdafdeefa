package naogateway.sim

import java.net.InetSocketAddress

import scala.concurrent.duration._

import akka.Done
import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.actor.typed.ActorRef
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.testkit.TestLoopback
import naogateway.wire.{Datagram, MessageContents, RpcReply, RpcValue}
import naogateway.wire.stream.{SecureStream, StreamSettings}

/** A simulated robot running the secure stream, over real loopback UDP, against a gateway-side [[SecureStream]] driven
  * by the test on a plain socket.
  */
class SimulatedRobotStreamSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike with LogCapturing {
  import SimulatedRobotStreamSpec._

  private def state(robot: ActorRef[SimulatedRobot.Command]): RobotView = {
    val probe = createTestProbe[RobotView]()
    robot ! SimulatedRobot.GetState(probe.ref)
    probe.receiveMessage(5.seconds)
  }

  private def stop(robot: ActorRef[SimulatedRobot.Command]): Unit = {
    val probe = createTestProbe[Done]()
    robot ! SimulatedRobot.Stop(probe.ref)
    probe.expectMessage(5.seconds, Done)
  }

  private val loremIpsum: String =
    "Lorem ipsum dolor sit amet, consectetur adipiscing elit, sed do eiusmod tempor incididunt ut labore et " +
      "dolore magna aliqua. Ut enim ad minim veniam, quis nostrud exercitation ullamco laboris nisi ut aliquip ex " +
      "ea commodo consequat. Duis aute irure dolor in reprehenderit in voluptate velit esse cillum dolore eu fugiat " +
      "nulla pariatur. Excepteur sint occaecat cupidatat non proident, sunt in culpa qui officia deserunt mollit " +
      "anim id est laborum."

  "A simulated robot with the secure stream" should {
    "receive a text through the stream over its module model, complete and in order, and restart at 0 after a power cycle" in {
      val gateway = new TestGateway
      try {
        val robot = spawn(SimulatedRobot(SimulatedRobotSettings(FirmwareSettings(robotId = 21), gateway.address,
              bindAddress = new InetSocketAddress(TestLoopback.address(), 0)).withStream()))
        val address = state(robot).address
        val driver = new GatewayStream(gateway, address, StreamSettings.thesis)

        // Each chunk goes as one speech.say frame; the robot's "output" is what it said, in order.
        val chunks = loremIpsum.grouped(37).toVector
        chunks.size % (StreamSettings.ThesisMaxSeq + 1) should not be 0
        chunks.zipWithIndex.foreach { case (chunk, i) =>
          driver.send(TestGateway.request("speech", "say", Vector(RpcValue.Text(chunk)), 100L + i), i.toLong)
        }
        driver.pumpUntil(20.seconds)(
          driver.acknowledged.size == chunks.size && driver.replies.size == chunks.size) shouldBe true

        val view = state(robot)
        view.said shouldBe chunks
        view.said.mkString shouldBe loremIpsum
        view.stats.streamSegments should be >= chunks.size.toLong
        view.module.map(_.readIntact).getOrElse(0L) should be >= chunks.size.toLong
        driver.replies.map(_.callId) shouldBe chunks.indices.map(i => Some(100L + i))
        all(driver.replies.map(_.result)) shouldBe Right(Some(RpcValue.Flag(true)))
        // The robot numbered its replies 0, 1, 2, … on its own side of the stream.
        withoutRepeats(driver.robotDataSequences) shouldBe chunks.indices.map(_ % (StreamSettings.ThesisMaxSeq + 1))

        robot ! SimulatedRobot.PowerCycle(300.millis)
        driver.pumpUntil(5.seconds)(driver.bootIds.contains(2)) shouldBe true
        // The gateway sees the new boot id and starts its end afresh, as both ends must (protocol.md 11.3).
        driver.reset()
        val before = driver.robotDataSequences.size
        driver.send(TestGateway.request("system", "ping", Vector.empty, 500L), 500L)
        driver.pumpUntil(5.seconds)(driver.replies.exists(_.callId.contains(500L))) shouldBe true
        withoutRepeats(driver.robotDataSequences.drop(before)) shouldBe Vector(0)
        driver.robotDataAcks.last shouldBe 0
        state(robot).stats.powerCycles shouldBe 1
        stop(robot)
      } finally gateway.close()
    }
  }
}

object SimulatedRobotStreamSpec {

  /** The sequence without immediate repeats: a retransmitted segment (a slow machine may time out) counts once. */
  def withoutRepeats(xs: Vector[Int]): Vector[Int] =
    xs.foldLeft(Vector.empty[Int])((acc, x) => if (acc.lastOption.contains(x)) acc else acc :+ x)

  /** The gateway's end of one robot's stream, on the test's plain socket, in real time. */
  final class GatewayStream(gateway: TestGateway, robot: InetSocketAddress, settings: StreamSettings) {
    private val origin = System.nanoTime()
    private def now(): Long = System.nanoTime() - origin

    private var stream = SecureStream.initial(settings, now())
    var acknowledged: Vector[Long] = Vector.empty
    var replies: Vector[RpcReply] = Vector.empty
    var bootIds: Set[Int] = Set.empty
    var robotDataSequences: Vector[Int] = Vector.empty
    var robotDataAcks: Vector[Int] = Vector.empty

    def send(payload: Array[Byte], id: Long): Unit =
      apply(stream.send(payload, id, None, now()).fold(r => throw new IllegalStateException(r.describe), identity))

    def reset(): Unit = apply(stream.reset(now()))

    /** Runs the stream on the socket until `done` or `within` has passed; whether `done` came true. */
    def pumpUntil(within: FiniteDuration)(done: => Boolean): Boolean = {
      val deadline = within.fromNow
      while (!done && deadline.hasTimeLeft()) {
        val untilTimer = stream.nextTimerAt.fold(20.millis)(t => math.max(1000000L, t - now()).nanos)
        gateway.receive(untilTimer.min(20.millis).min(deadline.timeLeft.max(1.millis))).foreach { heard =>
          // The robot's host, any port: it sends from its sending socket and receives at `robot`.
          if (heard.from.getAddress == robot.getAddress) onDatagram(heard.bytes)
        }
        if (stream.nextTimerAt.exists(_ <= now())) apply(stream.tick(now()))
      }
      done
    }

    private def onDatagram(bytes: Array[Byte]): Unit =
      Datagram.classify(bytes) match {
        case Datagram.StreamSegment(segment) =>
          if (segment.length > SecureStream.HeaderBytes) {
            robotDataSequences :+= segment(0) & 0xff
            robotDataAcks :+= segment(1) & 0xff
          }
          apply(stream.receive(segment, now()))
        case Datagram.FuRemoteFrame(frame) =>
          MessageContents.decodeFrame(frame).toOption.flatMap(_._2.robotHealth).flatMap(_.bootId).foreach(bootIds += _)
        case _ => ()
      }

    private def apply(step: SecureStream.Step): Unit = {
      stream = step.state
      step.outputs.foreach {
        case SecureStream.Transmit(d) => gateway.send(d, robot)
        case SecureStream.Deliver(payload) =>
          MessageContents.decodeFrame(payload).toOption.flatMap(_._2.rpcResponse).foreach(r =>
            replies :+= RpcReply.fromProto(r))
        case SecureStream.Acknowledged(id) => acknowledged :+= id
        case SecureStream.Expired(_)       => ()
      }
    }
  }
}
