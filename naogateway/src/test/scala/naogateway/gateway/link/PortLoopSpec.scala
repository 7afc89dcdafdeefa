package naogateway.gateway.link

import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel
import java.util.concurrent.{
  ConcurrentLinkedQueue,
  CountDownLatch,
  ExecutorService,
  Executors,
  LinkedBlockingQueue,
  RejectedExecutionException,
  ThreadFactory,
  TimeUnit
}
import java.util.concurrent.atomic.{AtomicBoolean, AtomicInteger}

import scala.jdk.CollectionConverters._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.testkit.TestLoopback
import naogateway.transport.PortLoop

/** The port loop alone, on loopback sockets: its tasks, its ports, and both together. */
class PortLoopSpec extends AnyWordSpec with Matchers {

  private val Wait = 10L // seconds any single step may take on a loaded machine before the spec fails

  /** Threads named `prefix-1`, `prefix-2`, … (one per executor), as Akka's thread factory names a dispatcher's. */
  private final class Named(prefix: String) extends ThreadFactory {
    private val n = new AtomicInteger
    def newThread(r: Runnable): Thread = new Thread(r, s"$prefix-${n.incrementAndGet()}")
  }

  private def loop(prefix: String, datagrams: Int = 256, tasks: Int = 64, answerSpinNanos: Long = 0L): PortLoop =
    new PortLoop(new Named(prefix), PortLoop.Settings(datagrams, tasks, answerSpinNanos))

  private def await(latch: CountDownLatch, what: String): Unit =
    if (!latch.await(Wait, TimeUnit.SECONDS)) fail(s"$what did not happen within $Wait s")

  /** Runs `body` on `executor` and returns its result, failing after the wait. */
  private def on[A](executor: ExecutorService)(body: => A): A = {
    val result = new LinkedBlockingQueue[Either[Throwable, A]]()
    executor.execute(() =>
      result.put(try Right(body)
        catch { case e: Throwable => Left(e) }))
    Option(result.poll(Wait, TimeUnit.SECONDS)).getOrElse(fail("the task did not run")).fold(throw _, identity)
  }

  /** What a port on the loop handed on, with the thread it ran on. */
  private final class Recorder extends RobotPort.Handler {
    val events = new LinkedBlockingQueue[(String, String)]() // (datagram's first byte or "caught up", thread)
    val count = new AtomicInteger
    @volatile var onReceived: () => Unit = () => ()
    def received(bytes: Array[Byte], from: InetSocketAddress): Unit = {
      count.incrementAndGet()
      events.put((bytes.headOption.fold("empty")(_.toString), Thread.currentThread().getName))
      onReceived()
    }
    def caughtUp(): Unit = events.put(("caught up", Thread.currentThread().getName))
    def gameControllerReceived(bytes: Array[Byte], from: InetSocketAddress): Unit = ()
    def next(): (String, String) =
      Option(events.poll(Wait, TimeUnit.SECONDS)).getOrElse(fail(s"nothing handed on within $Wait s"))
    def nextDatagram(): (String, String) = Iterator.continually(next()).find(_._1 != "caught up").get
  }

  private final class Fixture(prefix: String, datagrams: Int = 256, tasks: Int = 64, answerSpinNanos: Long = 0L) {
    val factory: PortLoop = loop(prefix, datagrams, tasks, answerSpinNanos)
    val executor: ExecutorService = factory.createExecutorService
    val robotAddress = new InetSocketAddress(TestLoopback.address(0), 0)
    val port: RobotPort = RobotPort.open(robotAddress, 1 << 20, s"$prefix-own-reader")
    val peer: DatagramChannel = DatagramChannel.open().bind(new InetSocketAddress(TestLoopback.address(0), 0))
    val recorder = new Recorder

    def send(first: Int, size: Int = 8): Unit = {
      val bytes = Array.fill[Byte](size)(0)
      bytes(0) = first.toByte
      peer.send(ByteBuffer.wrap(bytes), port.localAddress)
      ()
    }

    def close(): Unit =
      try port.close()
      finally {
        peer.close()
        executor.shutdown()
      }
  }

  private def withFixture[A](prefix: String, datagrams: Int = 256, tasks: Int = 64, answerSpinNanos: Long = 0L)(
      test: Fixture => A): A = {
    val f = new Fixture(prefix, datagrams, tasks, answerSpinNanos)
    try test(f)
    finally f.close()
  }

  private def alive(name: String): Boolean =
    Thread.getAllStackTraces.keySet.asScala.exists(t => t.getName == name && t.isAlive)

  "A port loop's executor" must {
    "run its tasks one after another, in the order they were given, on its one thread" in {
      val executor = loop("loop-fifo").createExecutorService
      try {
        val seen = new ConcurrentLinkedQueue[(Int, String)]()
        val done = new CountDownLatch(1)
        (1 to 2000).foreach(i => executor.execute(() => seen.add(i -> Thread.currentThread().getName)))
        executor.execute(() => done.countDown())
        await(done, "the last task")
        seen.asScala.map(_._1).toVector shouldBe (1 to 2000).toVector
        seen.asScala.map(_._2).toSet shouldBe Set("loop-fifo-1")
      } finally executor.shutdown()
    }
    "run a task given from another thread while it waits in its selector, every time" in {
      val executor = loop("loop-wake").createExecutorService
      try
        (1 to 200).foreach { i =>
          // Idle between tasks, so each one finds the loop in select(): a lost wake-up would leave it waiting.
          if (i % 20 == 0) Thread.sleep(5)
          val ran = new CountDownLatch(1)
          executor.execute(() => ran.countDown())
          await(ran, s"task $i")
        }
      finally executor.shutdown()
    }
    "refuse tasks once shut down, after running those given before" in {
      val executor = loop("loop-shutdown").createExecutorService
      val ran = new AtomicInteger
      val release = new CountDownLatch(1)
      executor.execute(() => release.await(Wait, TimeUnit.SECONDS))
      (1 to 10).foreach(_ => executor.execute(() => ran.incrementAndGet()))
      executor.shutdown()
      executor.isShutdown shouldBe true
      intercept[RejectedExecutionException](executor.execute(() => ran.incrementAndGet()))
      executor.isTerminated shouldBe false
      release.countDown()
      executor.awaitTermination(Wait, TimeUnit.SECONDS) shouldBe true
      ran.get shouldBe 10
      eventually(!alive("loop-shutdown-1"), "the thread ends")
    }
    "hand back the tasks not run on shutdownNow, and run none of them" in {
      val executor = loop("loop-now").createExecutorService
      val ran = new AtomicInteger
      val release = new CountDownLatch(1)
      val started = new CountDownLatch(1)
      executor.execute { () =>
        started.countDown()
        release.await(Wait, TimeUnit.SECONDS)
      }
      await(started, "the first task")
      (1 to 5).foreach(_ => executor.execute(() => ran.incrementAndGet()))
      executor.shutdownNow().size shouldBe 5
      release.countDown()
      executor.awaitTermination(Wait, TimeUnit.SECONDS) shouldBe true
      ran.get shouldBe 0
    }
  }

  "A robot port on a port loop" must {
    "hand each datagram to its handler on the loop's thread, then say it caught up" in
      withFixture("loop-read") { f =>
        f.port.startOn(f.recorder, f.executor)
        on(f.executor)(PortLoop.current) shouldBe Some(f.factory)
        f.port.onLoop shouldBe true
        f.port.readerAlive shouldBe false
        f.send(1)
        f.send(2)
        var seen = Vector.empty[(String, String)]
        while (seen.count(_._1 != "caught up") < 2 || seen.last._1 != "caught up") seen :+= f.recorder.next()
        seen.filter(_._1 != "caught up").map(_._1) shouldBe Vector("1", "2")
        seen.map(_._2).toSet shouldBe Set("loop-read-1")
        alive("loop-read-own-reader") shouldBe false
      }
    "let queued tasks run between batches of a flood of datagrams" in
      withFixture("loop-flood", datagrams = 4) { f =>
        f.port.startOn(f.recorder, f.executor)
        on(f.executor)(f.port.onLoop) shouldBe true
        // Hold the loop while 100 datagrams wait in the kernel, so the loop finds them all at once.
        val release = new CountDownLatch(1)
        val holding = new CountDownLatch(1)
        f.executor.execute { () =>
          holding.countDown()
          release.await(Wait, TimeUnit.SECONDS)
        }
        await(holding, "the loop held")
        val seenByTask = new LinkedBlockingQueue[Integer]()
        f.recorder.onReceived = { () =>
          if (f.recorder.count.get == 1) f.executor.execute(() => seenByTask.put(f.recorder.count.get))
        }
        (1 to 100).foreach(i => f.send(i))
        release.countDown()
        val seen = Option(seenByTask.poll(Wait, TimeUnit.SECONDS)).getOrElse(fail("the task did not run"))
        // Given at the first datagram, it ran after that pass's batch, long before the 100th.
        seen.intValue shouldBe 4
        eventually(f.recorder.count.get == 100, "all 100 datagrams arrive")
      }
    "read datagrams while a stream of tasks keeps its queue full" in
      withFixture("loop-stream", tasks = 4) { f =>
        f.port.startOn(f.recorder, f.executor)
        on(f.executor)(f.port.onLoop) shouldBe true
        val streaming = new AtomicBoolean(true)
        val ran = new AtomicInteger
        // A task that gives itself again: the queue is never empty while it runs (stopped at the end, or after 20 s).
        val deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(20)
        lazy val again: Runnable = () =>
          if (streaming.get && System.nanoTime() < deadline) {
            ran.incrementAndGet()
            f.executor.execute(again)
          }
        f.executor.execute(again)
        eventually(ran.get > 1000, "the stream runs")
        val during = new LinkedBlockingQueue[Integer]()
        f.recorder.onReceived = () => during.put(ran.get)
        f.send(7)
        val atArrival = Option(during.poll(Wait, TimeUnit.SECONDS)).getOrElse(fail("the datagram was starved"))
        // It arrived while the stream went on: the stream ran on after it.
        eventually(ran.get > atArrival.intValue + 100, "the stream goes on")
        streaming.set(false)
      }
    "be taken over by the next executor the loop makes, after the first one is shut down" in
      withFixture("loop-next") { f =>
        f.port.startOn(f.recorder, f.executor)
        on(f.executor)(f.port.onLoop) shouldBe true
        f.send(1)
        f.recorder.nextDatagram() shouldBe ("1" -> "loop-next-1")
        f.executor.shutdown()
        f.executor.awaitTermination(Wait, TimeUnit.SECONDS) shouldBe true
        // Shut down and idle, its thread still reads the port: it would be deaf until the next executor otherwise.
        f.send(2)
        f.recorder.nextDatagram() shouldBe ("2" -> "loop-next-1")
        val next = f.factory.createExecutorService
        try {
          on(next)(Thread.currentThread().getName) shouldBe "loop-next-2"
          eventually(!alive("loop-next-1"), "the first executor's thread ends")
          f.send(3)
          f.recorder.nextDatagram() shouldBe ("3" -> "loop-next-2")
          on(next)(PortLoop.current) shouldBe Some(f.factory)
        } finally {
          f.port.close()
          next.shutdown()
        }
        next.awaitTermination(Wait, TimeUnit.SECONDS) shouldBe true
        eventually(!alive("loop-next-2"), "the second executor's thread ends once the port is gone")
      }
    "stop calling the handler once close returns, and free the port" in
      withFixture("loop-close") { f =>
        f.port.startOn(f.recorder, f.executor)
        on(f.executor)(f.port.onLoop) shouldBe true
        // A flood from another thread while the port closes: nothing may reach the handler after close returns.
        val flooding = new AtomicBoolean(true)
        val flood = new Thread(() => {
          val deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(20)
          while (flooding.get && System.nanoTime() < deadline) {
            try f.send(5)
            catch { case _: java.io.IOException => () }
          }
        })
        flood.start()
        try {
          eventually(f.recorder.count.get > 50, "the flood arrives")
          f.port.close()
          val atClose = f.recorder.count.get
          Thread.sleep(100)
          f.recorder.count.get shouldBe atClose
          // The loop goes on running tasks, and the address can be bound again at once: the channel is closed.
          on(f.executor)(PortLoop.current) shouldBe Some(f.factory)
          DatagramChannel.open().bind(f.port.localAddress).close()
        } finally {
          flooding.set(false)
          flood.join(Wait * 1000)
        }
      }
    "close from the loop's own thread, in its handler, without waiting for itself" in
      withFixture("loop-self") { f =>
        f.port.startOn(f.recorder, f.executor)
        on(f.executor)(f.port.onLoop) shouldBe true
        f.recorder.onReceived = () => f.port.close()
        (1 to 20).foreach(i => f.send(i))
        f.recorder.nextDatagram()._1 shouldBe "1"
        // Closed by the first datagram's handler: the other 19 are never handed on, and the loop runs on.
        on(f.executor)(f.recorder.count.get) shouldBe 1
        DatagramChannel.open().bind(f.port.localAddress).close()
      }
    "read on a thread of its own when the executor is not a port loop's" in {
      val plain = Executors.newSingleThreadExecutor()
      val port = RobotPort.open(new InetSocketAddress(TestLoopback.address(0), 0), 1 << 16, "loop-fallback-reader")
      val peer = DatagramChannel.open().bind(new InetSocketAddress(TestLoopback.address(0), 0))
      try {
        val recorder = new Recorder
        port.startOn(recorder, plain)
        eventually(port.readerAlive, "the reader thread starts")
        port.onLoop shouldBe false
        peer.send(ByteBuffer.wrap(Array[Byte](9)), port.localAddress)
        recorder.nextDatagram() shouldBe ("9" -> "loop-fallback-reader")
        port.close()
        port.readerAlive shouldBe false
      } finally {
        peer.close()
        plain.shutdown()
      }
    }
    "not start reading when it is closed before the loop ran its start" in {
      val executor = loop("loop-early").createExecutorService
      val port = RobotPort.open(new InetSocketAddress(TestLoopback.address(0), 0), 1 << 16, "loop-early-reader")
      try {
        val release = new CountDownLatch(1)
        executor.execute(() => release.await(Wait, TimeUnit.SECONDS))
        port.startOn(new Recorder, executor)
        port.close()
        release.countDown()
        on(executor)(port.onLoop) shouldBe false
        port.readerAlive shouldBe false
      } finally executor.shutdown()
    }
  }

  "A port loop's answer spin" must {
    "never spin while nothing asked for an answer, however often tasks wake the loop" in
      withFixture("spin-idle", answerSpinNanos = 1000000L) { f =>
        f.port.startOn(f.recorder, f.executor)
        on(f.executor)(f.port.onLoop) shouldBe true
        (1 to 50).foreach { i =>
          if (i % 10 == 0) Thread.sleep(2) // idle between tasks: each one wakes the loop from select
          on(f.executor)(i)
          f.send(i)
          f.recorder.nextDatagram()._1 shouldBe i.toString
        }
        f.factory.spinCounts shouldBe ((0L, 0L))
      }
    "look for the answer to a request that just left before blocking, and hand it on from the spin" in
      withFixture("spin-answer", answerSpinNanos = 1000000L) { f =>
        f.port.startOn(f.recorder, f.executor)
        on(f.executor)(f.port.onLoop) shouldBe true
        // The answer is in the port before the spin starts (a loopback send is queued when it returns): the spin finds
        // it whatever the machine's load.
        f.executor.execute { () =>
          f.send(7)
          PortLoop.answerDue()
        }
        f.recorder.nextDatagram() shouldBe ("7" -> "spin-answer-1")
        f.factory.spinCounts shouldBe ((1L, 1L))
      }
    "count a spin that ran out as one, and take no due answer from another thread" in
      withFixture("spin-miss", answerSpinNanos = 20000L) { f =>
        f.port.startOn(f.recorder, f.executor)
        on(f.executor)(f.port.onLoop) shouldBe true
        PortLoop.answerDue() // not the loop's thread: nothing
        f.executor.execute(() => PortLoop.answerDue())
        eventually(f.factory.spinCounts._1 == 1L, "the spin")
        f.factory.spinCounts shouldBe ((1L, 0L))
      }
    "after 1, 2, 3 ... spins in a row ran out wait in select for the next 1, 3, 7 ... due answers, after a hit for none" in {
      val spin = new PortLoop.AnswerSpin(1000L)
      def spins(dues: Int, hit: Boolean): Int = (1 to dues).count { i =>
        spin.due(i.toLong)
        val due = spin.pending
        if (due) {
          spin.take() shouldBe i + 1000L
          spin.ended(hit)
        }
        due
      }
      spin.pending shouldBe false
      spins(1, hit = false) shouldBe 1 // missed: the next one waits
      spins(2, hit = false) shouldBe 1 // the second missed too: 3 wait
      spins(4, hit = false) shouldBe 1
      spins(8, hit = true) shouldBe 1 // 7 waited, then a hit
      spins(5, hit = true) shouldBe 5 // spun for every one since
      spins(1, hit = false) shouldBe 1
      (1 to PortLoop.AnswerSpin.MaxBackoff).foreach(k => spins(1 << k, hit = false) shouldBe 1)
      // The wait stays bounded: one spin in 1024 due answers, however many ran out.
      (1 to 3).foreach(_ => spins(1 << PortLoop.AnswerSpin.MaxBackoff, hit = false) shouldBe 1)
      val off = new PortLoop.AnswerSpin(0L)
      off.due(1L)
      off.pending shouldBe false
    }
  }

  /** Waits (bounded) until `condition` holds. */
  private def eventually(condition: => Boolean, what: String): Unit = {
    val deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(Wait)
    while (!condition) {
      if (System.nanoTime() > deadline) fail(s"$what did not happen within $Wait s")
      Thread.sleep(2)
    }
  }
}
