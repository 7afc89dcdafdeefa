package naogateway.launcher

import java.io.Closeable
import java.util.concurrent.atomic.AtomicBoolean
import java.util.concurrent.{
  ConcurrentHashMap,
  RejectedExecutionException,
  ScheduledFuture,
  ScheduledThreadPoolExecutor,
  ThreadFactory,
  TimeUnit
}

import scala.concurrent.ExecutionContext
import scala.concurrent.duration.FiniteDuration
import scala.util.control.NonFatal

import akka.actor.{Cancellable, Scheduler}
import akka.event.LoggingAdapter
import com.typesafe.config.Config

/** Akka's scheduler for a base station that is mostly idle (`akka.scheduler.implementation`, launcher.conf): timers are
  * rounded up to the next tick of `akka.scheduler.tick-duration` as with Akka's own scheduler, but its thread sleeps
  * until the earliest tick at which a timer is due instead of waking at every tick whether one is due or not (100 times
  * a second at Akka's 10 ms). Timers due at one tick fire at one wake-up, so bursts of short timers (the simulated
  * robots' link model) still fold into one wake-up as they do under Akka's scheduler. A due task is handed to its
  * executor, as Akka's does. Loaded by Akka with the system's config, a log and a thread factory.
  */
final class DeadlineScheduler(config: Config, log: LoggingAdapter, threadFactory: ThreadFactory)
    extends Scheduler
    with Closeable {

  private val timer = {
    val t = new ScheduledThreadPoolExecutor(1, threadFactory)
    // A cancelled timer leaves the queue at once: ask timeouts are cancelled by the thousand under load.
    t.setRemoveOnCancelPolicy(true)
    t.setExecuteExistingDelayedTasksAfterShutdownPolicy(false)
    t.setContinueExistingPeriodicTasksAfterShutdownPolicy(false)
    t
  }

  // What Akka's timer to an actor throws once the actor is gone (its class is Akka's own).
  private val TerminatedReceiver = "akka.actor.SchedulerException"

  // Tasks that must run when the scheduler closes (Akka marks them Scheduler.TaskRunOnClose), until they ran.
  private val runOnClose = ConcurrentHashMap.newKeySet[Runnable]()

  private val tickNanos: Long = {
    val tick = config.getDuration("akka.scheduler.tick-duration").toNanos
    require(tick > 0, "akka.scheduler.tick-duration must be above zero")
    tick
  }

  // The ticks count from here.
  private val origin = System.nanoTime()

  /** Ticks a second, as Akka's scheduler says it (the cluster reads it to choose whether it needs a scheduler of its
    * own).
    */
  override def maxFrequency: Double = 1e9 / tickNanos

  override def scheduleOnce(delay: FiniteDuration, runnable: Runnable)(implicit
      executor: ExecutionContext): Cancellable = {
    if (delay.toNanos <= 0L) {
      // Due now: to its executor from here, as Akka's scheduler does, without waking the timer's thread.
      if (timer.isShutdown) throw new IllegalStateException("the scheduler is closed")
      executor.execute(runnable)
      HandedOver
    } else {
      val closing = runnable.isInstanceOf[Scheduler.TaskRunOnClose]
      if (closing) runOnClose.add(runnable)
      val once = new Once(runnable, executor, closing)
      once.armed(arm(delay.toNanos, once))
      once
    }
  }

  @deprecated("use scheduleAtFixedRate or scheduleWithFixedDelay", "Akka 2.6.0")
  override def schedule(initialDelay: FiniteDuration, interval: FiniteDuration, runnable: Runnable)(implicit
      executor: ExecutionContext): Cancellable = {
    require(interval.toNanos > 0, "a repeated timer needs an interval above zero")
    val repeated = new Repeated(runnable, interval.toNanos, executor, System.nanoTime() + initialDelay.toNanos)
    repeated.armed(arm(initialDelay.toNanos, repeated.due))
    repeated
  }

  override def close(): Unit = {
    timer.shutdownNow()
    val it = runOnClose.iterator()
    while (it.hasNext) {
      val task = it.next()
      try task.run()
      catch { case NonFatal(e) => log.error(e, "A task run at the scheduler's close failed") }
    }
    runOnClose.clear()
  }

  // A timer that was due at once: handed over, too late to cancel.
  private val HandedOver: Cancellable = new Cancellable {
    override def cancel(): Boolean = false
    override def isCancelled: Boolean = false
  }

  // Schedules `fire` at the first tick at least `delayNanos` from now (at once for none); Akka's contract:
  // IllegalStateException once the scheduler is closed.
  private def arm(delayNanos: Long, fire: Runnable): ScheduledFuture[_] =
    try {
      val now = System.nanoTime()
      val delay =
        if (delayNanos <= 0L) 0L
        else {
          val due = now - origin + delayNanos
          origin + (due + tickNanos - 1) / tickNanos * tickNanos - now
        }
      timer.schedule(fire, delay, TimeUnit.NANOSECONDS)
    } catch {
      case _: RejectedExecutionException => throw new IllegalStateException("the scheduler is closed")
    }

  // Hands `task` to `executor` from the timer's thread; an executor already shut down drops it.
  private def hand(task: Runnable, executor: ExecutionContext): Unit =
    try executor.execute(task)
    catch { case NonFatal(e) => executor.reportFailure(e) }

  /** One timer: on the timer's thread it hands the task to its executor. Cancelling succeeds until then. */
  private final class Once(task: Runnable, executor: ExecutionContext, closing: Boolean)
      extends Runnable
      with Cancellable {
    private val state = new AtomicBoolean(false) // true once fired or cancelled
    @volatile private var cancelled = false
    @volatile private var future: ScheduledFuture[_] = _

    def armed(f: ScheduledFuture[_]): Unit = {
      future = f
      if (cancelled) f.cancel(false)
    }

    override def run(): Unit =
      if (state.compareAndSet(false, true)) {
        if (closing) runOnClose.remove(task)
        hand(task, executor)
      }

    override def cancel(): Boolean =
      if (state.compareAndSet(false, true)) {
        cancelled = true
        if (closing) runOnClose.remove(task)
        val f = future
        if (f ne null) f.cancel(false)
        true
      } else false

    override def isCancelled: Boolean = cancelled
  }

  /** A timer at a fixed rate: each run happens on the executor, and the next is armed after it, so runs never overlap
    * (a run longer than the interval delays the next, as with Akka's scheduler). A run that throws ends the timer.
    */
  private final class Repeated(task: Runnable, intervalNanos: Long, executor: ExecutionContext, firstAt: Long)
      extends Runnable
      with Cancellable {
    private val cancelled = new AtomicBoolean(false)
    @volatile private var future: ScheduledFuture[_] = _
    private var nextAt = firstAt // read and written by one run at a time

    /** What the timer's thread runs: hands this timer's run to the executor. */
    val due: Runnable = () => if (!cancelled.get) hand(this, executor)

    def armed(f: ScheduledFuture[_]): Unit = {
      future = f
      if (cancelled.get) f.cancel(false)
    }

    override def run(): Unit =
      if (!cancelled.get) {
        try {
          task.run()
          nextAt += intervalNanos
          armed(arm(nextAt - System.nanoTime(), due))
        } catch {
          // A closed scheduler, or a message to an actor that is gone: the timer ends quietly, as Akka's does.
          case _: IllegalStateException                                          => ()
          case e: akka.AkkaException if e.getClass.getName == TerminatedReceiver => ()
        }
      }

    override def cancel(): Boolean =
      if (!cancelled.compareAndSet(false, true)) false
      else {
        val f = future
        if (f ne null) f.cancel(false)
        true
      }

    override def isCancelled: Boolean = cancelled.get
  }
}
