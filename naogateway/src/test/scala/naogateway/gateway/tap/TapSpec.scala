package naogateway.gateway.tap

import java.net.InetSocketAddress
import java.util.concurrent.ConcurrentLinkedQueue
import java.util.concurrent.atomic.AtomicReference

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.api.GameReading
import naogateway.api.recording.{Decision, Tapped}
import naogateway.gateway.Routing
import naogateway.gateway.link.{PortReader, Relay}
import naogateway.proto.RecordedPort
import naogateway.transport.DatagramWriter
import naogateway.wire.gamecontroller.GameState

class TapSpec extends AnyWordSpec with Matchers {

  private val robot = new InetSocketAddress("127.0.0.5", 3838)
  private val port = new InetSocketAddress("127.0.0.1", 11011)

  private def received(tap: Tap, i: Int): Unit =
    tap.datagram(RecordedPort.ROBOT_PORT, received = true, robot, port, Array(i.toByte), 5)

  private def drain(reader: Tap.Reader): Vector[Tapped] = {
    val into = new java.util.ArrayList[Tapped]()
    reader.drainTo(into, Int.MaxValue)
    into.asScala.toVector
  }

  "The gateway's tap" should {
    "build nothing while no one reads it: a reader gets only what is published after it subscribed" in {
      val tap = new Tap
      tap.listening shouldBe false
      received(tap, 1)
      tap.decision(Decision.Gate(open = true, GameReading.Known(GameState.Initial)))
      val reader = tap.subscribe("late", 16)
      tap.listening shouldBe true
      drain(reader) shouldBe empty
      received(tap, 2)
      drain(reader).map { case d: Tapped.Datagram => d.bytes.toVector; case other => fail(s"$other") } shouldBe
        Vector(Vector(2.toByte))
    }

    "hand two readers every entry, the same one, in the order published" in {
      val tap = new Tap
      val a = tap.subscribe("a", 1024)
      val b = tap.subscribe("b", 1024)
      (1 to 100).foreach(received(tap, _))
      val gate = Decision.Gate(open = false, GameReading.Known(GameState.Playing))
      tap.decision(gate)
      val fromA = drain(a)
      val fromB = drain(b)
      fromA should have size 101
      fromA.zip(fromB).foreach { case (x, y) => x should be theSameInstanceAs y }
      fromA.init.map { case d: Tapped.Datagram => d.bytes(0).toInt; case other => fail(s"$other") } shouldBe
        (1 to 100).toVector
      fromA.last.asInstanceOf[Tapped.Decided].decision shouldBe gate
      tap.readers.map(r => (r.reader, r.delivered, r.dropped)) shouldBe Vector(("a", 101L, 0L), ("b", 101L, 0L))
    }

    "let a stalled reader drop and count what does not fit, while the other reader and the publisher go on" in {
      val tap = new Tap
      val stalled = tap.subscribe("stalled", 8)
      val reading = tap.subscribe("reading", 256)
      val got = Vector.newBuilder[Tapped]
      (1 to 10000).foreach { i =>
        received(tap, i)
        if (i % 100 == 0) got ++= drain(reading)
      }
      got.result() should have size 10000
      stalled.stats.dropped shouldBe 10000L - 8
      reading.stats.dropped shouldBe 0L
      drain(stalled) should have size 8
      tap.readers.find(_.reader == "stalled").map(_.dropped) shouldBe Some(9992L)
    }

    "forget a reader that leaves: nothing more is queued for it, and with none left nothing is built" in {
      val tap = new Tap
      val a = tap.subscribe("a", 16)
      val b = tap.subscribe("b", 16)
      a.close()
      received(tap, 1)
      drain(a) shouldBe empty
      drain(b) should have size 1
      tap.readers.map(_.reader) shouldBe Vector("b")
      b.close()
      tap.listening shouldBe false
      tap.readers shouldBe empty
    }

    "keep each publisher's order and lose nothing that fits while several threads publish and the reader drains" in {
      val tap = new Tap
      val reader = tap.subscribe("reader", 1 << 16)
      val perThread = 20000
      val publishers = (0 until 3).map { t =>
        new Thread(() =>
          (0 until perThread).foreach(i =>
            tap.datagram(RecordedPort.ROBOT_PORT, received = true, robot, port, Array(t.toByte), i)))
      }
      publishers.foreach(_.start())
      val got = Vector.newBuilder[Tapped.Datagram]
      var count = 0
      val into = new java.util.ArrayList[Tapped]()
      while (count < 3 * perThread && (publishers.exists(_.isAlive) || reader.pending > 0)) {
        into.clear()
        reader.drainTo(into, 1000)
        into.asScala.foreach { case d: Tapped.Datagram => got += d; count += 1; case _ => () }
      }
      publishers.foreach(_.join())
      into.clear()
      reader.drainTo(into, Int.MaxValue)
      into.asScala.foreach { case d: Tapped.Datagram => got += d; case _ => () }
      val all = got.result()
      reader.stats.dropped shouldBe 0L
      all should have size (3L * perThread)
      all.groupBy(_.bytes(0).toInt).values.foreach(ds => ds.map(_.robotId) shouldBe (0 until perThread))
    }

    "wake a reader waiting for entries when one is published" in {
      val tap = new Tap
      val reader = tap.subscribe("waiting", 16)
      val woke = new AtomicReference[Vector[Tapped]](Vector.empty)
      val thread = new Thread(() => {
        reader.await(60.seconds.toNanos)
        woke.set(drain(reader))
      })
      thread.start()
      received(tap, 7)
      thread.join(60000)
      thread.isAlive shouldBe false
      woke.get.size should be <= 1
      (woke.get ++ drain(reader)) should have size 1
    }

    "wake a reader gathering a batch only once the entries it waits for are there" in {
      // The recorder waits for a quarter batch after a batch it wrote: a trickle must not wake it per entry, and the
      // entry that completes the count must, long before the queue fills (Recorder.MaxParkNanos).
      val tap = new Tap
      val reader = tap.subscribe("gathering", 16)
      val woke = new java.util.concurrent.CountDownLatch(1)
      val thread = new Thread(() => { reader.await(60.seconds.toNanos, 3); woke.countDown() })
      thread.start()
      val parked = System.nanoTime() + 10.seconds.toNanos
      while (thread.getState != Thread.State.TIMED_WAITING && System.nanoTime() < parked) Thread.sleep(1)
      thread.getState shouldBe Thread.State.TIMED_WAITING
      received(tap, 1)
      received(tap, 2)
      woke.await(300, java.util.concurrent.TimeUnit.MILLISECONDS) shouldBe false // two of three: still waiting
      received(tap, 3)
      woke.await(60, java.util.concurrent.TimeUnit.SECONDS) shouldBe true
      thread.join(60000)
      drain(reader) should have size 3
    }
  }

  "The FU-Remote relay" should {
    "forward every datagram the robot port received, byte for byte, from the tap, and publish what it sent" in {
      val tap = new Tap
      val sent = new ConcurrentLinkedQueue[(Vector[Byte], InetSocketAddress)]()
      val link = new DatagramWriter {
        def send(bytes: Array[Byte], to: InetSocketAddress): Boolean = { sent.add(bytes.toVector -> to); true }
      }
      val fuRemote = new InetSocketAddress("127.0.0.9", 10000)
      val routes = new AtomicReference[Routing.Table[PortReader.Inlet]](Routing.Table.empty)
      val watcher = tap.subscribe("watcher", 1024)
      val relay =
        new Relay(PortReader.tapped(link, tap, RecordedPort.FU_REMOTE_RELAY, port, routes), fuRemote, tap, 1024,
          "tap-spec-relay")
      try {
        (1 to 50).foreach(received(tap, _))
        tap.datagram(RecordedPort.ROBOT_PORT, received = false, port, robot, Array(99.toByte), 5)
        tap.datagram(RecordedPort.GAME_CONTROLLER, received = true, robot, port, Array(98.toByte), -1)
        val deadline = 30.seconds.fromNow
        while (relay.relayed < 50 && deadline.hasTimeLeft()) Thread.sleep(10)
      } finally relay.close()
      relay.relayed shouldBe 50L
      sent.asScala.toVector shouldBe (1 to 50).map(i => Vector(i.toByte) -> fuRemote)
      val seen = drain(watcher).collect { case d: Tapped.Datagram if d.port == RecordedPort.FU_REMOTE_RELAY => d }
      seen.map(d => (d.received, d.destination, d.bytes.toVector)) shouldBe
        (1 to 50).map(i => (false, fuRemote, Vector(i.toByte)))
      tap.readers.map(_.reader) shouldBe Vector("watcher")
    }
  }
}
