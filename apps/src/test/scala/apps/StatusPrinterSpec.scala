package apps

import java.io.ByteArrayOutputStream
import java.net.{DatagramPacket, DatagramSocket, InetSocketAddress}
import java.nio.charset.StandardCharsets
import java.util.concurrent.ConcurrentLinkedQueue
import java.util.concurrent.atomic.{AtomicInteger, AtomicReference}

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.util.Using

import akka.actor.testkit.typed.scaladsl.ScalaTestWithActorTestKit
import org.jline.terminal.Size
import org.scalatest.wordspec.AnyWordSpecLike

import naogateway.integration.GatewayFixture

/** The status printer against a real gateway, fed the real GameController packets over loopback UDP. */
class StatusPrinterSpec extends ScalaTestWithActorTestKit with AnyWordSpecLike {

  /** A screen that keeps the last frame drawn. */
  private final class RecordingScreen extends StatusPrinter.ScreenOutput {
    val frame = new AtomicReference[Vector[String]](Vector.empty)
    val draws = new AtomicInteger()
    def draw(lines: Vector[String]): Unit = { frame.set(lines); draws.incrementAndGet() }
    def close(): Unit = ()
  }

  /** Sends the packet `file` to `to` until `seen` holds (at most 20 s, every 50 ms); fails if it never does. */
  private def sendUntil(to: InetSocketAddress, file: String)(seen: => Boolean): Unit = {
    val bytes = StatusViewSpec.vector(file)
    Using.resource(new DatagramSocket(new InetSocketAddress("127.0.0.1", 0))) { socket =>
      val deadline = 20.seconds.fromNow
      var ok = seen
      while (!ok && deadline.hasTimeLeft()) {
        socket.send(new DatagramPacket(bytes, bytes.length, to))
        Thread.sleep(50)
        ok = seen
      }
      withClue(s"after sending $file: ")(assert(ok))
    }
  }

  /** As [[sendUntil]], from one socket, with the version-8 packet number (byte 5) counting up from 1: the competition
    * gate opens only on a while of packets whose numbers follow one another (docs/protocol.md 10.7).
    */
  private def sendNumberedUntil(to: InetSocketAddress, file: String)(seen: => Boolean): Unit = {
    val bytes = StatusViewSpec.vector(file)
    Using.resource(new DatagramSocket(new InetSocketAddress("127.0.0.1", 0))) { socket =>
      val deadline = 20.seconds.fromNow
      var n = 1
      while (!seen && deadline.hasTimeLeft()) {
        bytes(5) = (n & 0xff).toByte
        socket.send(new DatagramPacket(bytes, bytes.length, to))
        n += 1
        Thread.sleep(50)
      }
      withClue(s"after sending $file: ")(assert(seen))
    }
  }

  private val competition = "competition.enabled = on\ngame-controller.trusted-sources = [\"127.0.0.0/8\"]\n" +
    "game-controller.max-trusted-range = 8\ngame-controller.gate-open-after = 1s"

  private def awaitTrue(what: String)(cond: => Boolean): Unit = {
    val deadline = 20.seconds.fromNow
    while (!cond && deadline.hasTimeLeft()) Thread.sleep(100)
    withClue(what)(assert(cond))
  }

  "The status printer" should {
    "print one line per change when piped: the robot, each game state of the real packets, and the competition gate" in {
      val fixture = new GatewayFixture(testKit, competition)
      try {
        val lines = new ConcurrentLinkedQueue[String]()
        val view = naogateway.gateway.GatewayReadView(fixture.gateway, 3.seconds)(system)
        spawn(StatusPrinter(view, 100.millis, StatusPrinter.LineOutput(l => lines.add(l))))
        fixture.robot(1)
        def printed = lines.asScala.toVector
        awaitTrue("robot 1 online")(printed.exists(l => l.startsWith("robot 1") && l.contains("online")))
        val gc = fixture.addresses.gameController.getOrElse(fail("no GameController port"))
        sendUntil(gc, "v8-initial.bin")(printed.exists(_.startsWith("game: INITIAL")))
        sendNumberedUntil(gc, "v8-initial.bin")(printed.contains("competition gate: open"))
        sendUntil(gc, "v8-ready.bin")(
          printed.exists(_.startsWith("game: READY, first half, 600 s left, secondary 30 s")))
        awaitTrue("gate closed")(printed.exists(_.startsWith("competition gate: CLOSED")))
        sendUntil(gc, "v8-set.bin")(printed.exists(_.startsWith("game: SET")))
        sendUntil(gc, "v8-playing.bin")(
          printed.contains("game: PLAYING, first half, 587 s left, score 2 : 1 (team 12 : team 7), version 8"))
        sendUntil(gc, "v7-playing.bin")(fixture.stats().gameControllerPackets >= 5)
        sendUntil(gc, "v8-finished.bin")(printed.exists(_.startsWith("game: FINISHED, second half")))
        sendNumberedUntil(gc, "v8-finished.bin")(printed.count(_ == "competition gate: open") == 2)
        // One line per change, not per packet: each packet above was sent at least once, some many times.
        printed.count(_.startsWith("game: PLAYING")) shouldBe 1
        printed.count(_.startsWith("competition gate: CLOSED: the game is running")) shouldBe 1
        // Competition mode started closed, and said so once.
        printed.count(_.startsWith("competition gate: CLOSED: no packet from the trusted GameController yet")) shouldBe
          1
      } finally fixture.stop()
    }

    "redraw a screen showing the robot with its link figures, the game of the real packets, the gate and the traffic" in {
      val fixture = new GatewayFixture(testKit, competition)
      try {
        val screen = new RecordingScreen
        spawn(StatusPrinter(naogateway.gateway.GatewayReadView(fixture.gateway, 3.seconds)(system), 100.millis, screen))
        fixture.robot(1)
        def frame = screen.frame.get
        /* "loss" shows a figure only once the gateway's read-only view answered GetLinkStats with the robot's link
         * figures. */
        awaitTrue("robot 1 with link figures")(frame.exists(l =>
            l.startsWith("robot 1") && l.contains("online") &&
              l.matches(".*loss \\d+ %.*")))
        val gc = fixture.addresses.gameController.getOrElse(fail("no GameController port"))
        sendUntil(gc, "v8-playing.bin")(
          frame.contains("game: PLAYING, first half, 587 s left, score 2 : 1 (team 12 : team 7), version 8"))
        awaitTrue("gate closed")(frame.exists(_.startsWith("competition gate: CLOSED")))
        awaitTrue("where game state comes from")(frame.exists(l =>
            l.startsWith("game state from 127.0.0.1:") &&
              l.contains("(trusted: 127.0.0.0/8)")))
        frame.exists(
          _.matches("team traffic: out [0-9.]+ kB/s, in [0-9.]+ kB/s, \\d+ % of the 125.0 kB/s budget.*")) shouldBe true
        sendUntil(gc, "v7-playing.bin")(fixture.stats().gameControllerPackets >= 2)
        sendUntil(gc, "v8-finished.bin")(frame.exists(_.startsWith("game: FINISHED")))
        sendNumberedUntil(gc, "v8-finished.bin")(frame.contains("competition gate: open"))
        frame.head shouldBe "naogateway - 1 robot(s), 1 online"
      } finally fixture.stop()
    }

    "restart after its output failed, and go on drawing" in {
      val fixture = new GatewayFixture(testKit)
      try {
        val draws = new AtomicInteger()
        val screen = new StatusPrinter.ScreenOutput {
          def draw(lines: Vector[String]): Unit =
            if (draws.incrementAndGet() == 1) throw new IllegalStateException("the terminal went away")
          def close(): Unit = ()
        }
        spawn(StatusPrinter(naogateway.gateway.GatewayReadView(fixture.gateway, 3.seconds)(system), 100.millis, screen))
        awaitTrue("drawn after the restart")(draws.get >= 3)
      } finally fixture.stop()
    }
  }

  "The choice of view" should {
    "take sbt's word that its console is a terminal when the JVM itself has none, and honour the override" in {
      assume(System.console() == null, "the test JVM runs on a terminal of its own")
      StatusPrinter.onTerminal(Map("NAOGATEWAY_TERMINAL" -> "true").get) shouldBe true
      StatusPrinter.onTerminal(Map("NAOGATEWAY_TERMINAL" -> "false").get) shouldBe false
      StatusPrinter.onTerminal(Map.empty[String, String].get) shouldBe false
      StatusPrinter.output(StatusPrinter.ViewMode.Lines) shouldBe a[StatusPrinter.LineOutput]
      Seq("auto", "Screen", " lines ").map(StatusPrinter.ViewMode.parse) shouldBe
        Seq(StatusPrinter.ViewMode.Auto, StatusPrinter.ViewMode.Screen, StatusPrinter.ViewMode.Lines)
      an[IllegalArgumentException] should be thrownBy StatusPrinter.ViewMode.parse("fancy")
    }
  }

  "The terminal screen" should {
    "draw the lines with JLine, rewrite only what changed, and nothing when nothing changed" in {
      val out = new ByteArrayOutputStream()
      val screen = TerminalScreen.over(out, Some("xterm-256color"), Some(new Size(100, 20)))
      val frame = Vector("naogateway - 1 robot(s), 1 online", "game: PLAYING, first half, 587 s left, score 2 : 1",
        "robot 1 online")
      screen.draw(frame)
      val first = out.toString(StandardCharsets.UTF_8)
      frame.foreach(first should include(_))
      out.reset()
      screen.draw(frame)
      out.size shouldBe 0
      screen.draw(frame.updated(2, "robot 1 offline"))
      // The text written, without the terminal's control sequences (cursor moves, attributes).
      val second = out.toString(StandardCharsets.UTF_8).replaceAll("\u001b\\[[0-9;?]*[A-Za-z]", "")
      // "online" became "offline": the cursor moves to the change and writes "ffline", nothing else.
      second should include("ffline")
      second should not include "robot 1"
      second should not include "game"
      screen.close()
    }
  }
}
