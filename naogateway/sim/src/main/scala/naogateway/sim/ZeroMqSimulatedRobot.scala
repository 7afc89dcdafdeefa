package naogateway.sim

import java.net.InetSocketAddress
import java.util.concurrent.TimeUnit

import scala.concurrent.duration._
import scala.util.control.NonFatal

import org.slf4j.LoggerFactory
import org.zeromq.{SocketType, ZContext, ZMQ, ZMsg}

import naogateway.wire.{HeaderForm, MessageContents, RpcReply}

/** A simulated robot of the original naogateway kind: the simulated CM-530 firmware's RPC modules behind a ZeroMQ REP
  * socket. A REP socket answers one request at a time, so a posture call holds the socket until its motion has ended,
  * exactly as a robot whose calls block would. It has its own thread (it stands for a separate machine), can be stopped
  * and started again (a power cycle: a new session, battery and position kept), and binds `endpoint`; with a port of
  * `*` the system picks one at the first start ([[boundEndpoint]]), and every later start binds that one again, as a
  * power-cycled robot keeps its address. `start` binds on the caller's thread; `stop` waits for the robot's thread to
  * end: call them from tests or tools, never from an actor.
  */
final class ZeroMqSimulatedRobot(settings: FirmwareSettings, val endpoint: String) {
  private val log = LoggerFactory.getLogger(classOf[ZeroMqSimulatedRobot])
  // Replies of the firmware go to this marker; everything else it emits (keep-alives, debug data) has nowhere to go.
  private val ReplyMarker = Destination.ReplyTo(new InetSocketAddress("127.0.0.1", 1))
  private val PollMillis = 20L
  private val LongestCall = 10.seconds

  @volatile private var state: Option[FirmwareState] = None
  @volatile private var running = false
  @volatile private var bound: Option[String] = None
  private var thread: Option[Thread] = None

  /** The firmware's state (for tests); `None` before the first start. */
  def firmware: Option[FirmwareState] = state

  /** The endpoint the socket is bound to, with the real port; `None` before the first start. */
  def boundEndpoint: Option[String] = bound

  /** Whether the robot is serving. */
  def isRunning: Boolean = running

  /** Binds the socket and starts serving; returns once bound, throws when the endpoint cannot be bound. The socket is
    * bound here, on the caller's thread, and handed to the robot's thread, whose start orders the two (ZeroMQ lets a
    * socket move between threads across such a barrier), so nothing waits for the other thread.
    */
  def start(): Unit = synchronized {
    require(!running, "the simulated robot is running already")
    val context = new ZContext(1)
    context.setLinger(0)
    val socket =
      try {
        val s = context.createSocket(SocketType.REP)
        s.setLinger(0)
        s.bind(bound.getOrElse(endpoint))
        s
      } catch { case NonFatal(e) => context.close(); throw e }
    bound = Some(socket.getLastEndpoint)
    val now = System.nanoTime()
    state = Some(state.fold(RobotFirmware.boot(settings, now))(s => RobotFirmware.restart(s, now)))
    running = true
    val t = new Thread(() => serve(context, socket), s"zmq-sim-robot-${settings.robotId}")
    t.setDaemon(true)
    t.start()
    thread = Some(t)
  }

  /** Stops serving: the socket is closed and the thread has ended when this returns. */
  def stop(): Unit = synchronized {
    running = false
    thread.foreach { t =>
      t.join(5000)
      if (t.isAlive) log.warn("Simulated ZeroMQ robot [{}] did not stop within 5 s", settings.robotId)
    }
    thread = None
  }

  private def serve(context: ZContext, socket: ZMQ.Socket): Unit =
    try {
      log.info("Simulated ZeroMQ robot [{}] serving on {}", settings.robotId, socket.getLastEndpoint)
      val poller = context.createPoller(1)
      poller.register(socket, ZMQ.Poller.POLLIN)
      while (running) {
        advanceTo(System.nanoTime())
        poller.poll(PollMillis)
        if (poller.pollin(0)) {
          val request = ZMsg.recvMsg(socket, ZMQ.DONTWAIT)
          if (request != null) {
            val body = if (request.size() > 0) request.getLast.getData else Array.emptyByteArray
            request.destroy()
            val reply = answer(body)
            // A robot stopped in the middle of a call answers nothing: the caller's timeout handles it.
            if (running) socket.send(reply, 0)
          }
        }
      }
      poller.close()
    } catch {
      case NonFatal(e) => log.error("Simulated ZeroMQ robot [{}] failed", settings.robotId, e)
    } finally {
      context.close()
      log.info("Simulated ZeroMQ robot [{}] stopped", settings.robotId)
    }

  private def advanceTo(now: Long): Vector[Outgoing] = {
    val (next, out) = RobotFirmware.advance(state.get, now)
    state = Some(next)
    out.filter(_.to == ReplyMarker)
  }

  /** The one reply to one request: what the firmware answers, waiting for it when the call ends later (posture). */
  private def answer(body: Array[Byte]): Array[Byte] =
    MessageContents.parse(body) match {
      case Left(error) =>
        val id = state.map(_.settings.robotId).getOrElse(settings.robotId)
        MessageContents(id,
          rpcResponse = Some(RpcReply(Left(s"bad parameters: not a Message (${error.describe})")).toProto)).toProtobuf
      case Right(contents) =>
        val (next, out) = RobotFirmware.onMessage(state.get, HeaderForm.Legacy, contents, ReplyMarker)
        state = Some(next)
        var replies = out.filter(_.to == ReplyMarker)
        val deadline = System.nanoTime() + LongestCall.toNanos
        // A posture call answers when its motion has ended: hold the request, as the REP socket forces us to. The wait
        // is on this robot's own thread (it stands for the robot's blocking loop), never an actor's or a dispatcher's.
        def waiting = contents.rpcRequest.isDefined && !replies.exists(isRpcReply)
        while (waiting && running && System.nanoTime() < deadline) {
          val wait =
            math.max(0L, math.min(state.get.nextWakeUp - System.nanoTime(), TimeUnit.MILLISECONDS.toNanos(PollMillis)))
          if (wait > 0) Thread.sleep(wait / 1000000L, (wait % 1000000L).toInt)
          replies = replies ++ advanceTo(System.nanoTime())
        }
        val merged = replies.flatMap(o => MessageContents.decodeFrame(o.bytes).toOption.map(_._2)).foldLeft(
          MessageContents(next.settings.robotId)) {
          (acc, c) =>
            acc.copy(
              rpcResponse = acc.rpcResponse.orElse(c.rpcResponse),
              debuggingCommands = acc.debuggingCommands.orElse(c.debuggingCommands)
            )
        }
        merged.toProtobuf
    }

  private def isRpcReply(o: Outgoing): Boolean =
    MessageContents.decodeFrame(o.bytes).exists(_._2.rpcResponse.isDefined)
}
