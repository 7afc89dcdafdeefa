package naogateway.transport

import java.nio.ByteBuffer
import java.nio.channels.Pipe
import java.util.concurrent.ConcurrentLinkedQueue
import java.util.concurrent.atomic.AtomicBoolean

import scala.concurrent.duration.FiniteDuration
import scala.concurrent.{Future, Promise}
import scala.util.control.NonFatal

import akka.Done
import org.slf4j.LoggerFactory
import org.zeromq.{SocketType, ZContext, ZMQ}

/** One thread of ZeroMQ: a context, its sockets and a poll loop. ZeroMQ sockets must stay on one thread, so actors
  * never touch them: they `submit` operations, which the loop runs on its own thread between polls. The loop blocks in
  * `poll`, so it runs on a dedicated dispatcher, never on the actors' one.
  */
final class ZeroMqLoop(val name: String, pollTimeout: FiniteDuration) extends Runnable {
  require(pollTimeout.toMillis >= 1, "the poll timeout must be at least 1 ms")

  private val log = LoggerFactory.getLogger(classOf[ZeroMqLoop])
  private val operations = new ConcurrentLinkedQueue[ZeroMqLoop.Sockets => Unit]()
  // A pipe in the poll set lets another thread end a poll at once instead of after the timeout.
  private val wakeUp = Pipe.open()
  wakeUp.source.configureBlocking(false)
  wakeUp.sink.configureBlocking(false)
  private val wakePending = new AtomicBoolean(false)
  private val started = new AtomicBoolean(false)
  @volatile private var stopping = false
  private val done = Promise[Done]()

  /** Runs `operation` on the loop's thread; false when the loop is stopping (the operation is then dropped). */
  def submit(operation: ZeroMqLoop.Sockets => Unit): Boolean =
    if (stopping) false
    else {
      operations.add(operation)
      wake()
      true
    }

  /** Starts the loop on `executor` (once). */
  def start(executor: java.util.concurrent.Executor): Unit =
    if (started.compareAndSet(false, true)) executor.execute(this)

  /** Asks the loop to end: operations submitted before still run (so last replies go out), then the sockets and the
    * context are closed. Completes when the thread has left the loop.
    */
  def stop(): Future[Done] = {
    stopping = true
    if (started.compareAndSet(false, true)) {
      // Never started: nothing to close but the pipe.
      closePipe()
      done.trySuccess(Done)
    } else wake()
    done.future
  }

  /** Completes when the loop's thread has left the loop and the context is terminated. */
  def terminated: Future[Done] = done.future

  private def wake(): Unit =
    if (wakePending.compareAndSet(false, true)) {
      try wakeUp.sink.write(ByteBuffer.wrap(Array[Byte](1)))
      catch { case NonFatal(_) => () } // a full or closed pipe: the loop is awake or gone anyway
    }

  private def closePipe(): Unit = {
    try wakeUp.sink.close()
    catch { case NonFatal(_) => () }
    try wakeUp.source.close()
    catch { case NonFatal(_) => () }
  }

  def run(): Unit = {
    val thread = Thread.currentThread()
    val threadName = thread.getName
    thread.setName(s"$threadName-$name")
    val context = new ZContext(1)
    context.setLinger(0)
    val sockets = new ZeroMqLoop.Sockets(context)
    var poller: ZMQ.Poller = null
    var pollerItems = Vector.empty[ZMQ.Socket]
    val drain = ByteBuffer.allocate(64)
    log.debug("ZeroMQ loop [{}] started", name)
    try {
      while (!stopping) {
        wakePending.set(false)
        var operation = operations.poll()
        while (operation != null && !stopping) {
          try operation(sockets)
          catch { case NonFatal(e) => log.error("ZeroMQ loop [{}]: an operation failed", name, e) }
          operation = operations.poll()
        }
        if (!stopping) {
          if (poller == null || sockets.changed) {
            if (poller != null) poller.close()
            pollerItems = sockets.readable
            poller = context.createPoller(pollerItems.size + 1)
            poller.register(wakeUp.source, ZMQ.Poller.POLLIN)
            pollerItems.foreach(s => poller.register(s, ZMQ.Poller.POLLIN))
            sockets.changed = false
          }
          poller.poll(pollTimeout.toMillis)
          if (poller.pollin(0)) {
            drain.clear()
            while (wakeUp.source.read(drain) > 0) drain.clear()
          }
          var i = 0
          while (i < pollerItems.size && !stopping) {
            if (poller.pollin(i + 1)) {
              try sockets.dispatch(pollerItems(i))
              catch { case NonFatal(e) => log.error("ZeroMQ loop [{}]: a socket handler failed", name, e) }
            }
            i += 1
          }
        }
      }
    } catch {
      case NonFatal(e) => log.error("ZeroMQ loop [{}] failed; closing its sockets", name, e)
    } finally {
      stopping = true
      var operation = operations.poll()
      while (operation != null) {
        try operation(sockets)
        catch { case NonFatal(e) => log.warn("ZeroMQ loop [{}]: an operation failed while stopping", name, e) }
        operation = operations.poll()
      }
      try {
        if (poller != null) poller.close()
        context.close()
      } catch { case NonFatal(e) => log.warn("ZeroMQ loop [{}]: closing the context failed", name, e) }
      closePipe()
      log.debug("ZeroMQ loop [{}] ended", name)
      thread.setName(threadName)
      done.trySuccess(Done)
    }
  }
}

/** The loop's side: sockets and their handlers, used only on the loop's thread. */
object ZeroMqLoop {

  /** Messages read from one socket per wake-up at most, so one busy socket cannot starve the others. */
  val ReadBatch: Int = 256

  /** Creating, watching and closing sockets; only ever called on the loop's thread (inside `submit`). */
  final class Sockets private[ZeroMqLoop] (context: ZContext) {
    private var handlers = Map.empty[ZMQ.Socket, ZMQ.Socket => Boolean]
    private var order = Vector.empty[ZMQ.Socket]
    private[ZeroMqLoop] var changed = false

    /** A new socket of `kind` that drops unsent messages when closed (no linger). */
    def socket(kind: SocketType): ZMQ.Socket = {
      val s = context.createSocket(kind)
      s.setLinger(0)
      s
    }

    /** Calls `read` while `socket` has input; `read` takes one message with `ZMQ.DONTWAIT` and returns false when there
      * was none.
      */
    def onReadable(socket: ZMQ.Socket)(read: ZMQ.Socket => Boolean): Unit = {
      if (!handlers.contains(socket)) order = order :+ socket
      handlers = handlers.updated(socket, read)
      changed = true
    }

    /** Stops watching `socket` and closes it. */
    def close(socket: ZMQ.Socket): Unit = {
      if (handlers.contains(socket)) {
        handlers -= socket
        order = order.filterNot(_ eq socket)
        changed = true
      }
      socket.close()
    }

    private[ZeroMqLoop] def readable: Vector[ZMQ.Socket] = order

    private[ZeroMqLoop] def dispatch(socket: ZMQ.Socket): Unit =
      handlers.get(socket).foreach { read =>
        var n = 0
        while (n < ReadBatch && read(socket)) n += 1
      }
  }
}
