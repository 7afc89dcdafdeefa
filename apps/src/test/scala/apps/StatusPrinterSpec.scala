package apps

import java.io.ByteArrayOutputStream
import java.net.{DatagramPacket, DatagramSocket, InetSocketAddress}
import java.nio.charset.StandardCharsets
import java.util.concurrent.ConcurrentLinkedQueue
import java.util.concurrent.atomic.{AtomicInteger, AtomicReference}

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

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

  /** The test's GameController: one socket, as a real GameController sends every packet from one address (a packet from
    * a second socket would be a second GameController, whose packets the gateway ignores while the first one sends).
    * Version-8 packets carry a packet number (byte 5) counting up from 1 across all of them: the competition gate opens
    * only on a while of packets whose numbers follow one another (docs/protocol.md 10.7).
    */
  private final class TestGameController(to: InetSocketAddress) extends AutoCloseable {
    private val socket = new DatagramSocket(new InetSocketAddress("127.0.0.1", 0))
    private var number = 0

    /** Sends the packet `file` until `seen` holds (at most 20 s, every 50 ms); fails if it never does. */
    def sendUntil(file: String)(seen: => Boolean): Unit = {
      val bytes = StatusViewSpec.vector(file)
      val numbered = file.startsWith("v8-")
      val deadline = 20.seconds.fromNow
      var ok = seen
      while (!ok && deadline.hasTimeLeft()) {
        if (numbered) {
          number += 1
          bytes(5) = (number & 0xff).toByte
        }
        socket.send(new DatagramPacket(bytes, bytes.length, to))
        Thread.sleep(50)
        ok = seen
      }
      withClue(s"after sending $file: ")(assert(ok))
    }

    def close(): Unit = socket.close()
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
        val gc = new TestGameController(fixture.addresses.gameController.getOrElse(fail("no GameController port")))
        try {
          gc.sendUntil("v8-initial.bin")(printed.exists(_.startsWith("game: INITIAL")))
          gc.sendUntil("v8-initial.bin")(printed.contains("competition gate: open"))
          gc.sendUntil("v8-ready.bin")(
            printed.exists(_.startsWith("game: READY, first half, 600 s left, secondary 30 s")))
          awaitTrue("gate closed")(printed.exists(_.startsWith("competition gate: CLOSED")))
          gc.sendUntil("v8-set.bin")(printed.exists(_.startsWith("game: SET")))
          gc.sendUntil("v8-playing.bin")(
            printed.contains("game: PLAYING, first half, 587 s left, score 2 : 1 (team 12 : team 7), version 8"))
          gc.sendUntil("v7-playing.bin")(fixture.stats().gameControllerPackets >= 5)
          gc.sendUntil("v8-finished.bin")(printed.exists(_.startsWith("game: FINISHED, second half")))
          gc.sendUntil("v8-finished.bin")(printed.count(_ == "competition gate: open") == 2)
        } finally gc.close()
        // One GameController, one socket: never taken for two.
        printed.filter(_.contains("GameControllers on this field")) shouldBe empty
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
        val gc = new TestGameController(fixture.addresses.gameController.getOrElse(fail("no GameController port")))
        try {
          gc.sendUntil("v8-playing.bin")(
            frame.contains("game: PLAYING, first half, 587 s left, score 2 : 1 (team 12 : team 7), version 8"))
          awaitTrue("gate closed")(frame.exists(_.startsWith("competition gate: CLOSED")))
          awaitTrue("where game state comes from")(frame.exists(l =>
              l.startsWith("game state from 127.0.0.1:") &&
                l.contains("(trusted: 127.0.0.0/8)")))
          frame.exists(
            _.matches(
              "team traffic: out [0-9.]+ kB/s, in [0-9.]+ kB/s, \\d+ % of the 125.0 kB/s budget.*")) shouldBe true
          gc.sendUntil("v7-playing.bin")(fixture.stats().gameControllerPackets >= 2)
          gc.sendUntil("v8-finished.bin")(frame.exists(_.startsWith("game: FINISHED")))
          gc.sendUntil("v8-finished.bin")(frame.contains("competition gate: open"))
        } finally gc.close()
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
    "read the controlling terminal's size once, and again only when the terminal signals a resize (WINCH)" in {
      val reads = new java.util.concurrent.atomic.AtomicInteger()
      @volatile var current = new Size(100, 20)
      val out = new ByteArrayOutputStream()
      val screen = TerminalScreen.over(out, Some("xterm-256color"), fixedSize = None,
        readSize = () => { reads.incrementAndGet(); Some(current) })
      reads.get shouldBe 1
      val frame = Vector("x" * 90)
      screen.draw(frame)
      out.toString(StandardCharsets.UTF_8) should include("x" * 90)
      // Redraws ask nothing of the terminal.
      (1 to 5).foreach(_ => screen.draw(frame))
      reads.get shouldBe 1
      current = new Size(40, 20)
      val kill = new ProcessBuilder("kill", "-WINCH", ProcessHandle.current().pid().toString).start()
      kill.waitFor() shouldBe 0
      val deadline = 10.seconds.fromNow
      while (reads.get < 2 && deadline.hasTimeLeft()) Thread.sleep(10)
      reads.get shouldBe 2
      out.reset()
      screen.draw(frame)
      // Fitted to the new width: the line no longer fits whole.
      out.toString(StandardCharsets.UTF_8) should not include ("x" * 90)
      screen.close()
      // A closed screen follows no more resizes: the next WINCH reaches a second screen, not the first.
      val others = new java.util.concurrent.atomic.AtomicInteger()
      val second = TerminalScreen.over(new ByteArrayOutputStream(), Some("xterm-256color"), fixedSize = None,
        readSize = () => { others.incrementAndGet(); Some(current) })
      new ProcessBuilder("kill", "-WINCH", ProcessHandle.current().pid().toString).start().waitFor() shouldBe 0
      val again = 10.seconds.fromNow
      while (others.get < 2 && again.hasTimeLeft()) Thread.sleep(10)
      others.get shouldBe 2
      reads.get shouldBe 2
      second.close()
    }
  }
}
