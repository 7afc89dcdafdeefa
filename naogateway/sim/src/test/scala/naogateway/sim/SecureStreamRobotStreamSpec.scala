package naogateway.sim

import java.net.{InetAddress, InetSocketAddress}
import java.nio.charset.StandardCharsets.US_ASCII

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.wire.stream.{SecureStream, StreamSettings}

class SecureStreamRobotStreamSpec extends AnyWordSpec with Matchers {

  private def gatewaySends(gateway: SecureStream, text: String, id: Long, now: Long): SecureStream.Step =
    gateway.send(text.getBytes(US_ASCII), id, None, now).fold(r => fail(r.describe), identity)

  private def transmitted(step: SecureStream.Step): Vector[Array[Byte]] =
    step.outputs.collect { case SecureStream.Transmit(d) => d }

  "The robot's secure-stream adapter" should {
    "deliver the gateway's payloads and transmit the robot's ACKs and replies as segments" in {
      val robot = SecureStreamRobotStream.factory()(0L)
      val g1 = gatewaySends(SecureStream.initial(StreamSettings.thesis, 0L), "Lorem", 1L, 0L)
      val segment = transmitted(g1).head
      segment.toVector.take(2) shouldBe Vector[Byte](0, 20)

      val r1 = robot.receive(segment, 1000L)
      r1.deliver.map(new String(_, US_ASCII)) shouldBe Vector("Lorem")
      r1.transmit.map(_.toVector) shouldBe Vector(Vector[Byte](20, 0))

      val r2 = r1.stream.send("OK".getBytes(US_ASCII), 2000L)
      r2.deliver shouldBe empty
      r2.transmit.map(_.toVector) shouldBe Vector(Vector[Byte](0, 0, 'O'.toByte, 'K'.toByte))

      // The gateway's side takes both and acknowledges the reply.
      val g2 = g1.state.receive(r1.transmit.head, 3000L)
      g2.outputs should contain(SecureStream.Acknowledged(1L))
      val g3 = g2.state.receive(r2.transmit.head, 4000L)
      g3.outputs.collect { case SecureStream.Deliver(p) => new String(p, US_ASCII) } shouldBe Vector("OK")
    }
    "map timers through, and drop a reply its endpoint refuses" in {
      val robot = SecureStreamRobotStream.factory()(0L)
      // Fresh: nothing to repair, no timer (protocol.md 11.3); received data earns one idle ACK.
      robot.nextTimerAt shouldBe None
      val answered = robot.receive(Array[Byte](0, 20, 'x'), 0L).stream
      answered.nextTimerAt shouldBe Some(StreamSettings.thesis.idleAckInterval.toNanos)
      answered.tick(answered.nextTimerAt.get).transmit.map(_.toVector) shouldBe Vector(Vector[Byte](20, 0))
      val refused = robot.send(Array.emptyByteArray, 5L)
      refused.transmit shouldBe empty
      refused.stream shouldBe a[SecureStreamRobotStream]
      refused.stream.asInstanceOf[SecureStreamRobotStream].refused shouldBe 1L
    }
    "start every endpoint it builds afresh, at sequence number 0, whatever the previous one had reached" in {
      val factory = SecureStreamRobotStream.factory()
      val used =
        (0 until 5).foldLeft(factory(0L): RobotStream)((s, i) => s.send(Array[Byte](1, i.toByte), i.toLong).stream)
      used.asInstanceOf[SecureStreamRobotStream].state.nextSequence shouldBe 1
      val fresh = factory(10L).asInstanceOf[SecureStreamRobotStream].state
      fresh.nextSequence shouldBe 0
      fresh.lastInOrder shouldBe StreamSettings.ThesisMaxSeq
      fresh.settings shouldBe StreamSettings.thesis
    }
    "be what withStream plugs into a robot and every robot of a fleet" in {
      val gateway = new InetSocketAddress(InetAddress.getLoopbackAddress, 11011)
      val robot =
        SimulatedRobotSettings(FirmwareSettings(robotId = 1), gateway).withStream(StreamSettings.selectiveRepeat(4))
      robot.stream.map(_(0L)).collect { case s: SecureStreamRobotStream => s.state.settings.window } shouldBe Some(4)
      val fleet = Fleet.robotSettings(FleetSettings.ofSize(3, gateway).withStream())
      all(fleet.map(_.stream.map(_(0L).getClass))) shouldBe Some(classOf[SecureStreamRobotStream])
    }
  }
}
