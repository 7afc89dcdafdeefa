package naogateway.launcher

import java.util.concurrent.{ConcurrentLinkedQueue, CountDownLatch, TimeUnit}

import scala.concurrent.ExecutionContext
import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

import akka.actor.testkit.typed.scaladsl.ActorTestKit
import akka.actor.typed.scaladsl.Behaviors
import com.typesafe.config.ConfigFactory
import org.scalatest.BeforeAndAfterAll
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** The launcher's scheduler in an actor system as the package runs it: timers fire in the order they are due and never
  * early, a cancelled one never does, a repeated one repeats until cancelled, and actors' timers work on it.
  */
class DeadlineSchedulerSpec extends AnyWordSpec with Matchers with BeforeAndAfterAll {

  private val testKit = ActorTestKit(
    "deadline-scheduler",
    ConfigFactory.parseString(s"akka.scheduler.implementation = ${classOf[DeadlineScheduler].getName}")
      .withFallback(ActorTestKit.ApplicationTestConfig)
  )
  private val scheduler = testKit.system.classicSystem.scheduler
  private implicit val ec: ExecutionContext = testKit.system.executionContext

  override def afterAll(): Unit = testKit.shutdownTestKit()

  private def await(latch: CountDownLatch): Unit = latch.await(10, TimeUnit.SECONDS) shouldBe true

  "The deadline scheduler" should {
    "be the actor system's scheduler" in {
      scheduler shouldBe a[DeadlineScheduler]
    }

    "run one-shot timers in the order they are due, never a cancelled one" in {
      val ran = new ConcurrentLinkedQueue[String]()
      val done = new CountDownLatch(1)
      scheduler.scheduleOnce(300.millis)(ran.add("late")).isCancelled shouldBe false
      val cancelled = scheduler.scheduleOnce(100.millis)(ran.add("cancelled"))
      scheduler.scheduleOnce(50.millis)(ran.add("early"))
      scheduler.scheduleOnce(0.millis)(ran.add("now"))
      scheduler.scheduleOnce(400.millis) { ran.add("last"); done.countDown() }
      cancelled.cancel() shouldBe true
      cancelled.isCancelled shouldBe true
      cancelled.cancel() shouldBe false
      await(done)
      ran.asScala.toVector shouldBe Vector("now", "early", "late", "last")
    }

    "never run a timer before its delay, which it rounds up to the scheduler's tick" in {
      val done = new CountDownLatch(1)
      val start = System.nanoTime()
      @volatile var ranAfter = 0L
      scheduler.scheduleOnce(25.millis) { ranAfter = System.nanoTime() - start; done.countDown() }
      await(done)
      ranAfter should be >= 25.millis.toNanos
      scheduler.maxFrequency shouldBe 100.0 // the tests' tick, 10 ms
    }

    "not cancel a timer that has run" in {
      val done = new CountDownLatch(1)
      val timer = scheduler.scheduleOnce(1.millis)(done.countDown())
      await(done)
      timer.cancel() shouldBe false
      timer.isCancelled shouldBe false
    }

    "hand a timer due at once to its executor, too late to cancel" in {
      val done = new CountDownLatch(1)
      val timer = scheduler.scheduleOnce(0.millis)(done.countDown())
      timer.cancel() shouldBe false
      timer.isCancelled shouldBe false
      await(done)
    }

    "repeat a timer at its rate until it is cancelled" in {
      val runs = new java.util.concurrent.atomic.AtomicInteger()
      val three = new CountDownLatch(3)
      val timer = scheduler.scheduleAtFixedRate(0.millis, 10.millis) { () =>
        runs.incrementAndGet()
        three.countDown()
      }
      await(three)
      timer.cancel() shouldBe true
      val after = runs.get()
      // A run already handed to the dispatcher may still come; nothing after it.
      val later = new CountDownLatch(1)
      scheduler.scheduleOnce(100.millis)(later.countDown())
      await(later)
      runs.get() should be <= after + 1
      timer.isCancelled shouldBe true
    }

    "end a repeated timer whose run throws" in {
      val runs = new java.util.concurrent.atomic.AtomicInteger()
      scheduler.scheduleAtFixedRate(0.millis, 5.millis) { () =>
        runs.incrementAndGet()
        throw new IllegalArgumentException("the run fails")
      }
      val later = new CountDownLatch(1)
      scheduler.scheduleOnce(200.millis)(later.countDown())
      await(later)
      runs.get() shouldBe 1
    }

    "drive actors' timers" in {
      val probe = testKit.createTestProbe[String]()
      testKit.spawn(Behaviors.withTimers[String] { timers =>
        timers.startTimerWithFixedDelay("tick", 20.millis)
        Behaviors.receiveMessage { m =>
          probe.ref ! m
          Behaviors.same
        }
      })
      probe.receiveMessages(3, 10.seconds) shouldBe Seq("tick", "tick", "tick")
    }
  }

  "A closed deadline scheduler" should {
    "refuse new timers and run the tasks marked to run at close" in {
      val own =
        new DeadlineScheduler(ConfigFactory.parseString("akka.scheduler.tick-duration = 10ms"), akka.event.NoLogging,
          (r: Runnable) => new Thread(r, "deadline-scheduler-spec"))
      val ran = new ConcurrentLinkedQueue[String]()
      own.scheduleOnce(1.hour,
        new Runnable with akka.actor.Scheduler.TaskRunOnClose {
          def run(): Unit = { ran.add("on close"); () }
        })
      own.scheduleOnce(1.hour)(ran.add("dropped"))
      own.close()
      ran.asScala.toVector shouldBe Vector("on close")
      an[IllegalStateException] should be thrownBy own.scheduleOnce(1.millis)(ran.add("after close"))
    }
  }
}
