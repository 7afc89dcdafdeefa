package naogateway.transport

import java.io.IOException
import java.nio.ByteBuffer
import java.nio.channels.{ClosedChannelException, SelectableChannel, SelectionKey, Selector}
import java.util.concurrent.{
  AbstractExecutorService,
  ConcurrentLinkedQueue,
  CountDownLatch,
  ExecutorService,
  RejectedExecutionException,
  ThreadFactory,
  TimeUnit
}
import java.util.concurrent.locks.{LockSupport, ReentrantLock}
import java.{util => ju}

import scala.util.control.NonFatal

import akka.dispatch.{
  DispatcherPrerequisites,
  ExecutorServiceConfigurator,
  ExecutorServiceFactory,
  MonitorableThreadFactory
}
import com.typesafe.config.Config
import org.slf4j.LoggerFactory

/** One thread that runs an Akka dispatcher's tasks and reads the datagram ports attached to it (the gateway's robot
  * port, the apps' datagram door).
  *
  * Why: with the port read by a thread of its own, a robot's answer wakes that reader (epoll), and the reader wakes the
  * robot dispatcher's thread (a mailbox). Here the thread that runs the robot actors waits in the ports' selector
  * whenever it has no task, so an answer wakes one thread only, and what the reader hands the actors is queued on the
  * thread that is already running. The cost: reading and routing no longer run beside the actors.
  *
  * Akka makes one of these per dispatcher ([[PortLoopConfigurator]]) and asks it for a new executor service after it
  * shut an idle one down; the selector and the attached ports belong to this object, so each executor's thread takes
  * them over from the one before. One executor's thread at a time owns the selector (`ownership`).
  */
final class PortLoop private[naogateway] (threadFactory: ThreadFactory, settings: PortLoop.Settings)
    extends ExecutorServiceFactory {
  import PortLoop._

  // Held by the executor thread that runs the loop, for its whole run; whoever holds it owns the selector, the
  // attachments' registrations and `attachedCount`.
  private val ownership = new ReentrantLock()
  // Opened by the owning thread when it starts, closed by it when it ends with no port attached (a test JVM makes many
  // actor systems: an idle dispatcher must not keep an epoll descriptor).
  @volatile private var selector: Selector = null
  // The executor whose thread should own the loop: the newest one.
  @volatile private var latest: Generation = null
  // Detaches asked for by threads other than the loop's; done by the owner.
  private val detaches = new ConcurrentLinkedQueue[Attachment]()
  private var attachedCount = 0
  // Failed selects, by the owning thread only.
  private var selectFailures = 0L
  // One buffer for the loop's life, used by the owning thread only; each datagram is copied out at its own size.
  private lazy val buffer = ByteBuffer.allocateDirect(DatagramPort.MaxDatagramBytes)
  // The answer spin ([[PortLoop.answerDue]]): by the owning thread only.
  private val answerSpin = new AnswerSpin(settings.answerSpinNanos)
  // Spins and the spins something ended, for the bench and the specs; written by the owner only.
  @volatile private var spins = 0L
  @volatile private var spinHits = 0L

  /** How many times the loop polled for a due answer instead of waiting in select, and how many of those an answer (a
    * datagram, or a task) ended before the spin ran out.
    */
  def spinCounts: (Long, Long) = (spins, spinHits)

  /** A new executor; its thread runs the loop once the previous executor's thread has let it go. */
  def createExecutorService: ExecutorService = {
    val generation = new Generation
    latest = generation
    wakeup() // an earlier executor's thread, serving ports only after its shutdown, lets go now
    generation.start()
    generation
  }

  /** Reads `source`'s channel on this loop from now on; on the loop's own thread only ([[PortLoop.current]]). */
  private[naogateway] def attach(source: Source): Attachment = {
    require(ownership.isHeldByCurrentThread, "a port is attached on its loop's own thread")
    val attachment = new Attachment(source)
    attachment.key = source.channel.register(selector, SelectionKey.OP_READ, attachment)
    attachedCount += 1
    attachment
  }

  private def wakeup(): Unit = {
    val s = selector
    if (s != null) s.wakeup()
  }

  // By the owner only.
  private def remove(attachment: Attachment): Unit = {
    unregister(attachment)
    attachment.done.countDown()
  }

  private def unregister(attachment: Attachment): Unit =
    if (!attachment.detached) {
      attachment.detached = true
      attachment.key.cancel()
      attachedCount -= 1
    }

  // By the owner only, never while it walks the selected keys.
  private def processDetaches(): Unit = {
    var a = detaches.poll()
    if (a != null) {
      var done = List.empty[Attachment]
      while (a != null) {
        unregister(a)
        done ::= a
        a = detaches.poll()
      }
      // A channel still registered with a selector is closed only at that selector's next select: this one lets go of
      // the cancelled keys now, so the port closed after the detach is free at once (bound again by a restart).
      val s = selector
      if (s != null && s.isOpen)
        try s.selectNow()
        catch { case NonFatal(e) => log.warn("Port loop: letting go of a port failed: {}", e.toString) }
      done.foreach(_.done.countDown())
    }
  }

  /** A port's place on the loop: the loop reads it until [[Attachment.detach]]. */
  final class Attachment private[PortLoop] (private[PortLoop] val source: Source) {
    @volatile private[PortLoop] var detached = false
    private[PortLoop] var key: SelectionKey = null
    private[PortLoop] val done = new CountDownLatch(1)

    /** Stops the loop reading the port; once it returns true the source's `drain` is not called any more. Waits at most
      * `waitMillis` for the loop's thread to finish a batch it is reading; on the loop's own thread it does not wait.
      * False when the wait ran out.
      */
    def detach(waitMillis: Long): Boolean =
      if (ownership.isHeldByCurrentThread) {
        // On the loop (a task, or the handler itself): nothing else can be reading the port now.
        remove(this)
        true
      } else {
        detaches.add(this)
        val deadline = System.nanoTime() + TimeUnit.MILLISECONDS.toNanos(waitMillis)
        var left = waitMillis
        while (done.getCount > 0 && left > 0) {
          // No thread owns the loop (between executors): the caller may detach it itself. Otherwise the owner does it
          // at its next pass, which the wake-up starts now.
          if (ownership.tryLock())
            try processDetaches()
            finally ownership.unlock()
          else wakeup()
          done.await(math.min(left, DetachRetryMillis), TimeUnit.MILLISECONDS)
          left = TimeUnit.NANOSECONDS.toMillis(deadline - System.nanoTime())
        }
        done.getCount == 0
      }
  }

  /** One executor service: its own task queue and thread, over the loop's selector and ports. */
  private final class Generation extends AbstractExecutorService {
    private val tasks = new ConcurrentLinkedQueue[Runnable]()
    // True while the thread is in (or about to enter) select(): only then does a task from another thread wake it.
    @volatile private var selecting = false
    @volatile private var shut = false
    private val finished = new CountDownLatch(1)
    private val thread = threadFactory.newThread(() => run())

    def start(): Unit = thread.start()

    def execute(task: Runnable): Unit = {
      if (task eq null) throw new NullPointerException("task")
      if (shut) throw new RejectedExecutionException("the port loop's executor is shut down")
      tasks.add(task)
      // A shutdown between the check and the add: the task either runs (the thread took it) or is refused, never lost.
      if (shut && tasks.remove(task)) throw new RejectedExecutionException("the port loop's executor is shut down")
      // From the loop's own thread `selecting` is false: no wake-up system call per task.
      if (selecting) wakeup()
    }

    def shutdown(): Unit = {
      shut = true
      wakeup()
    }

    def shutdownNow(): ju.List[Runnable] = {
      shut = true
      val left = new ju.ArrayList[Runnable]()
      var t = tasks.poll()
      while (t != null) {
        left.add(t)
        t = tasks.poll()
      }
      // No interrupt: a thread interrupted while it reads a channel closes that channel (an attached port).
      wakeup()
      left
    }

    def isShutdown: Boolean = shut

    /** Every task is done; the thread may still read attached ports until the next executor takes them over. */
    def isTerminated: Boolean = finished.getCount == 0

    def awaitTermination(timeout: Long, unit: TimeUnit): Boolean = finished.await(timeout, unit)

    private def run(): Unit = {
      ownership.lock()
      try {
        if (selector == null || !selector.isOpen) selector = Selector.open()
        loopThread.set(PortLoop.this)
        passes()
      } finally {
        loopThread.remove()
        finished.countDown()
        processDetaches()
        if (attachedCount == 0 && selector != null) {
          try selector.close()
          catch { case NonFatal(e) => log.warn("Port loop: closing its selector failed: {}", e.toString) }
        }
        ownership.unlock()
      }
    }

    private def passes(): Unit = {
      var taking = true // false once shut down and every task ran; then the thread only reads ports
      var serving = true
      while (serving) {
        processDetaches()
        if (taking) {
          runTasks(settings.tasksPerPass)
          if (shut && tasks.isEmpty) {
            taking = false
            finished.countDown()
          }
        }
        // After its shutdown the thread keeps reading the attached ports (they would be deaf otherwise) until the next
        // executor's thread takes them over or they are detached.
        if (!taking && (attachedCount == 0 || (latest ne this))) serving = false
        else {
          // An interrupted thread's select returns at once, and its next read would close the channel.
          Thread.interrupted()
          // An answer due within microseconds is looked for before the thread blocks: the wake-up from select would
          // cost more than the wait. Only after a request left (never when idle), and bounded.
          if (answerSpin.pending && taking && tasks.isEmpty && detaches.isEmpty && !shut) spinForAnswer()
          selecting = true
          val mustNotWait = !detaches.isEmpty || !selector.selectedKeys().isEmpty ||
            (if (taking) shut || !tasks.isEmpty else latest ne this)
          try {
            if (mustNotWait) selector.selectNow() else selector.select()
          } catch {
            // The thread runs every robot actor: it must outlive a failing select. Counted, logged at a bounded rate,
            // and not retried at once, so a failure that repeats cannot spin a core.
            case e: IOException =>
              selectFailures += 1
              if (RateLimitedLog.due(selectFailures))
                log.warn("Port loop: select failed ({} so far): {}", selectFailures, e.toString)
              LockSupport.parkNanos(1000000L)
          }
          selecting = false
          // The selected keys, not select's count: a key still selected from an earlier select is not counted again.
          if (!selector.selectedKeys().isEmpty) readReady()
        }
      }
    }

    /** Polls the ports and the task queue until something arrives or the spin's time is up ([[AnswerSpin]]);
      * `selecting` stays false, so a task from another thread costs no wake-up system call meanwhile.
      */
    private def spinForAnswer(): Unit = {
      val until = answerSpin.take()
      spins += 1
      // Polled at least once, even when the tasks before it ran past the spin's time.
      var arrived = false
      var polling = true
      try
        while (polling) {
          if (!tasks.isEmpty || !detaches.isEmpty || shut || (latest ne this)) arrived = true
          else if (selector.selectNow() > 0 || !selector.selectedKeys().isEmpty) arrived = true
          polling = !arrived && System.nanoTime() - until < 0
          if (polling) Thread.onSpinWait()
        }
      catch {
        case e: IOException =>
          selectFailures += 1
          if (RateLimitedLog.due(selectFailures))
            log.warn("Port loop: select failed ({} so far): {}", selectFailures, e.toString)
      }
      if (arrived) spinHits += 1
      answerSpin.ended(arrived)
    }

    private def runTasks(limit: Int): Unit = {
      var n = 0
      while (n < limit) {
        val task = tasks.poll()
        if (task eq null) n = limit
        else {
          n += 1
          try task.run()
          catch {
            case NonFatal(e) =>
              val t = Thread.currentThread()
              Option(t.getUncaughtExceptionHandler).fold(log.error("Port loop: a task failed", e))(
                _.uncaughtException(t, e))
          }
        }
      }
    }

    private def readReady(): Unit = {
      val keys = selector.selectedKeys().iterator()
      while (keys.hasNext) {
        val key = keys.next()
        keys.remove()
        val attachment = key.attachment().asInstanceOf[Attachment]
        if (!attachment.detached && key.isValid) {
          try attachment.source.drain(buffer, settings.datagramsPerPass)
          catch {
            case _: ClosedChannelException => remove(attachment) // closed after a detach that ran out of time
            case NonFatal(e)               => log.error("Port loop: reading a port failed", e)
          }
        }
      }
    }
  }
}

/** The loop of the calling thread, the loop's settings and what a port hands it. */
object PortLoop {

  /** Datagrams read from one port per pass, and tasks run per pass: neither a flood of datagrams nor a stream of tasks
    * starves the other.
    */
  final case class Settings(datagramsPerPass: Int, tasksPerPass: Int, answerSpinNanos: Long = 0L) {
    require(datagramsPerPass >= 1 && tasksPerPass >= 1, "a pass reads at least one datagram and runs at least one task")
    require(answerSpinNanos >= 0 && answerSpinNanos <= MaxAnswerSpinNanos, "the answer spin is 0 to 1 ms")
  }

  /** Reading the settings. */
  object Settings {

    /** From a dispatcher's `port-loop` block (naogateway's reference.conf); a block without `answer-spin` does not
      * spin.
      */
    def apply(config: Config): Settings =
      Settings(config.getInt("datagrams-per-pass"), config.getInt("tasks-per-pass"),
        if (config.hasPath("answer-spin")) config.getDuration("answer-spin").toNanos else 0L)
  }

  /** Tells the calling thread's loop, if it runs on one, that a datagram asking for an answer left just now (a request
    * to a robot, which answers every request at once): the loop looks for the answer for up to `answer-spin` before it
    * blocks. Nothing on any other thread.
    */
  def answerDue(): Unit = {
    val loop = loopThread.get
    if (loop != null) loop.answerSpin.due(System.nanoTime())
  }

  // The longest answer spin allowed.
  private val MaxAnswerSpinNanos = 1000000L

  /** When the loop spins for an answer: for `spinNanos` after a request left, unless recent spins ran out. A spin that
    * runs out makes the next 1, 2, 4 … up to 1024 due answers wait in select (misses in a row double it), so a robot
    * that answers slower than the spin (over WiFi) costs next to no spinning, and one that answers within it is spun
    * for every time. Used by the loop's owning thread only.
    */
  private[naogateway] final class AnswerSpin(spinNanos: Long) {
    private var waiting = false
    private var until = 0L
    private var misses = 0
    private var skips = 0L

    /** Whether an answer is due: the loop spins before it blocks. */
    def pending: Boolean = waiting

    /** A request left at `now`. */
    def due(now: Long): Unit =
      if (spinNanos > 0) {
        if (skips > 0) skips -= 1
        else {
          waiting = true
          until = now + spinNanos
        }
      }

    /** The spin's deadline (System.nanoTime), the due answer taken. */
    def take(): Long = {
      waiting = false
      until
    }

    /** The spin ended: `hit` when something arrived before its deadline. */
    def ended(hit: Boolean): Unit =
      if (hit) misses = 0
      else {
        misses = math.min(misses + 1, AnswerSpin.MaxBackoff)
        skips = (1L << misses) - 1
      }
  }

  private[naogateway] object AnswerSpin {
    // Misses in a row the backoff counts: 2^10 - 1 due answers waited for in select before the next spin.
    val MaxBackoff = 10
  }

  /** What the loop reads: a non-blocking channel, and how to hand on what is in it. */
  private[naogateway] trait Source {

    /** The channel the loop waits on. */
    private[naogateway] def channel: SelectableChannel

    /** Reads at most `max` datagrams with `buffer`, handing each on; tells its handler it caught up once the channel is
      * empty. Throws ClosedChannelException once the channel is closed.
      */
    private[naogateway] def drain(buffer: ByteBuffer, max: Int): Unit
  }

  private val loopThread = new ThreadLocal[PortLoop]

  /** The loop the calling thread runs, if it is a port loop's thread. */
  def current: Option[PortLoop] = Option(loopThread.get)

  // A detach that finds the loop busy looks again this often (only when the wake-up and the owner's exit crossed).
  private val DetachRetryMillis = 10L

  private val log = LoggerFactory.getLogger(classOf[PortLoop])
}

/** Makes Akka run a dispatcher on a [[PortLoop]]: `executor = "naogateway.transport.PortLoopConfigurator"` in the
  * dispatcher's block, with a `port-loop` block of [[PortLoop.Settings]].
  */
final class PortLoopConfigurator(config: Config, prerequisites: DispatcherPrerequisites)
    extends ExecutorServiceConfigurator(config, prerequisites) {
  private val settings = PortLoop.Settings(config.getConfig("port-loop"))

  /** The dispatcher's one loop; its threads are named after the dispatcher, as Akka names a fork-join pool's. */
  def createExecutorServiceFactory(id: String, threadFactory: ThreadFactory): ExecutorServiceFactory = {
    val named = threadFactory match {
      case m: MonitorableThreadFactory => m.withName(m.name + "-" + id)
      case other                       => other
    }
    new PortLoop(named, settings)
  }
}
