package naogateway.sim

import java.net.InetSocketAddress

import naogateway.wire.{BusBridgeFrame, Datagram}

/** What a simulated robot does with one datagram its firmware has read, and where its firmware's answers go: pure steps
  * over its [[SimulatedRobot.Robot]] state, apart from the actor that owns the sockets ([[SimulatedRobotRun]]).
  */
private[sim] object RobotDatagrams {
  import SimulatedRobot._

  /** One datagram the firmware has read: a stream segment goes to the stream, anything else to the firmware. */
  def handle(robot: Robot, bytes: Array[Byte], from: InetSocketAddress, at: Long, gateway: InetSocketAddress,
      logCalls: (Array[Byte], Long) => Unit): (Robot, Vector[Out], Vector[Outgoing]) =
    Datagram.classify(bytes) match {
      case Datagram.StreamSegment(segment) =>
        val counted = robot.copy(stats = robot.stats.copy(streamSegments = robot.stats.streamSegments + 1))
        counted.stream.fold((counted, Vector.empty[Out], Vector.empty[Outgoing])) { stream =>
          val step = stream.receive(segment, at)
          var next = counted.copy(stream = Some(step.stream))
          val app = Vector.newBuilder[Outgoing]
          // Each delivered payload is one frame from the gateway; its replies go back through the stream.
          step.deliver.filter(Datagram.isFuRemoteFrame).foreach { frame =>
            val when = math.max(at, next.firmware.now)
            BusBridgeFrame.decode(frame).map(_._2) match {
              case Some(request) =>
                // A bridged bus request (docs/protocol.md 6.9): one reply, back through the stream.
                val (firmware, reply) = RobotFirmware.busBridge(next.firmware, request, when)
                next = next.copy(firmware = firmware)
                app += Outgoing(reply, Destination.ReplyTo(ThroughStream))
              case None =>
                logCalls(frame, at)
                val (firmware, out) = RobotFirmware.receive(next.firmware, frame, ThroughStream, when, viaStream = true)
                next = next.copy(firmware = firmware)
                app ++= out
            }
          }
          (next, step.transmit.map(Out(_, gateway)), app.result())
        }
      case _ if BusBridgeFrame.mayCarry(bytes) && BusBridgeFrame.decode(bytes).isDefined =>
        // A bus bridge frame travels only in the secure stream (docs/protocol.md 6.9): a plain one is dropped, counted.
        (robot.copy(stats = robot.stats.copy(busBridgeDropped = robot.stats.busBridgeDropped + 1)), Vector.empty,
          Vector.empty)
      case _ =>
        logCalls(bytes, at)
        val (firmware, out) = RobotFirmware.receive(robot.firmware, bytes, from, at)
        (robot.copy(firmware = firmware), Vector.empty, out)
    }

  /** Where the firmware's datagrams go: replies to stream requests into the stream, everything else on the air. */
  def route(robot: Robot, outgoing: Vector[Outgoing], t: Long, gateway: InetSocketAddress): (Robot, Vector[Out]) = {
    var next = robot
    val plain = Vector.newBuilder[Out]
    outgoing.foreach {
      case Outgoing(bytes, Destination.Gateway) => plain += Out(bytes, gateway)
      case Outgoing(bytes, Destination.ReplyTo(ThroughStream)) =>
        next.stream.foreach { s =>
          val step = s.send(bytes, t)
          next = next.copy(stream = Some(step.stream))
          plain ++= step.transmit.map(Out(_, gateway))
        }
      case Outgoing(bytes, Destination.ReplyTo(to)) => plain += Out(bytes, to)
    }
    (next, plain.result())
  }
}
