package apps.control

import java.io.{BufferedReader, InputStreamReader}
import java.net.{InetSocketAddress, Socket}
import java.nio.charset.StandardCharsets

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import akka.actor.typed.ActorRef
import akka.actor.typed.scaladsl.Behaviors
import com.typesafe.config.ConfigFactory
import org.scalatest.wordspec.AnyWordSpecLike

/** The control port as any TCP client sees it: one request line in, lines out, then the connection closes. */
class ControlServerSpec extends ScalaTestWithActorTestKit(ConfigFactory.load()) with AnyWordSpecLike with LogCapturing {

  private val settings = ControlSettings(system).copy(host = "127.0.0.1", port = 0)
  private val fleet = new FleetStub(1000)
  private lazy val server = spawn(ControlServer.withInterface(fleet, settings), "control")
  private lazy val port = address(server).getPort

  private def address(server: ActorRef[ControlServer.Command]): InetSocketAddress = {
    val probe = createTestProbe[InetSocketAddress]()
    server ! ControlServer.GetAddress(probe.ref)
    probe.receiveMessage(10.seconds)
  }

  private def connect(port: Int): Socket = {
    val socket = new Socket()
    socket.connect(new InetSocketAddress("127.0.0.1", port), 5000)
    socket.setSoTimeout(30000)
    socket
  }

  /** Everything the server sends until it closes. */
  private def linesOf(socket: Socket): Vector[String] = {
    val in = new BufferedReader(new InputStreamReader(socket.getInputStream, StandardCharsets.UTF_8))
    try Iterator.continually(in.readLine()).takeWhile(_ != null).toVector
    finally socket.close()
  }

  /** The lines answering `request` (sent as bytes, so anything can be sent). */
  private def send(request: Array[Byte], serverPort: Int, thenClose: Boolean = false): Vector[String] = {
    val socket = connect(serverPort)
    socket.getOutputStream.write(request)
    socket.getOutputStream.flush()
    if (thenClose) socket.shutdownOutput()
    linesOf(socket)
  }

  private def exchange(line: String, serverPort: Int = port): Vector[String] =
    send((line + "\n").getBytes(StandardCharsets.UTF_8), serverPort)

  "The control port" should {
    "stream a status of 1,000 robots as one short line per robot, then ok" in {
      val lines = exchange("status")
      lines.size shouldBe 1 + 1000 + 1
      lines.head should startWith(". id   address")
      lines.last shouldBe "ok"
      val robots = lines.slice(1, 1001)
      robots.map(_.drop(2).split("\\s+")(0).toInt) shouldBe (1 to 1000)
      robots.foreach(l => l.length should be < 200)
      robots.head.split("\\s+").toList shouldBe List(".", "1", "127.0.0.1:20001", "online", "good", "12.25", "V", "sit",
        "striker", "1.5", "ms", "25", "%", "±1.4", "ms", "+250", "ppm", "-")
      robots(9) should include("offline  offline")
      // Each robot's lease holders, and a robot the middleware holds safe (FleetStub: 2's walk is teleop's, 3 is held).
      robots(1) should endWith(" walk=teleop")
      robots(2) should endWith(" - HELD SAFE")
    }

    "take the lease a motion call needs and give it back; calls that need none take none" in {
      exchange("call 2 motion walk n:0.2 n:0.0 n:0.0") shouldBe Vector(
        ". robot 2: motion.walk -> Text(motion.walk(Number(0.2),Number(0.0),Number(0.0)))", "ok")
      exchange("call 3 system ping") shouldBe Vector(". robot 3: system.ping -> Text(system.ping())", "ok")
      fleet.history should contain inOrderElementsOf Vector("acquire 2 walk", "call 2 motion.walk", "release 2 walk",
        "call 3 system.ping")
      fleet.history should not contain "acquire 3 system"
      // A read takes no lease, so it works while another app holds the robot (motion.getPosture is a read).
      exchange("call 4 motion getPosture") shouldBe Vector(". robot 4: motion.getPosture -> Text(motion.getPosture())",
        "ok")
      fleet.history should contain("call 4 motion.getPosture")
      fleet.history.filter(_.startsWith("acquire 4")) shouldBe empty
    }

    "answer a failing call, an unknown robot and a bad request with one error line" in {
      exchange("call 5 system ping") shouldBe Vector("error robot 5: no such method")
      exchange("call 5000 system ping") shouldBe Vector("error no robot 5000 is known")
      exchange("watch 5000 2") shouldBe Vector("error no robot 5000 is known")
      exchange("hello gateway") shouldBe Vector("error unknown request 'hello gateway'")
      exchange("watch 1 7200") shouldBe Vector("error a watch lasts at most 3600 s")
      send(Array[Byte](0, -1, -2, 10), port) shouldBe Vector("error unknown request '\\\\u0000\ufffd\ufffd'")
    }

    "refuse an overlong request line, and an empty one" in {
      // One write, so that the whole line is read before the refusal: a client that goes on sending after it
      // may see its connection reset instead, as TCP does when a socket closes with input unread.
      send(Array.fill[Byte](5000)('x'.toByte) :+ '\n'.toByte, port) shouldBe Vector(
        "error request line longer than 4096 bytes")
      send(Array.emptyByteArray, port, thenClose = true) shouldBe Vector("error no request line")
      send("status".getBytes(StandardCharsets.UTF_8), port, thenClose = true).last shouldBe "ok"
    }

    "stream a watch and end it with ok" in {
      val lines = exchange("watch 4 1")
      lines.head should startWith(". id")
      lines.slice(1, lines.size - 1).foreach(_ should startWith(". 4 "))
      lines.last shouldBe "ok watched robot 4 for 1 s"
    }

    "serve at most max-connections at once, tell the others it is busy, and time out a silent client" in {
      val small =
        spawn(ControlServer.withInterface(fleet, settings.copy(maxConnections = 1, requestTimeout = 3.seconds)))
      val smallPort = address(small).getPort
      val silent = connect(smallPort)
      // The silent client holds the one slot until its request timeout (3 s, far longer than a local connect takes).
      exchange("status", smallPort) shouldBe Vector("error busy: 1 robotctl commands are being served; try again")
      linesOf(silent) shouldBe Vector("error no request line within 3 s")
      // The slot is free again.
      eventually(exchange("status", smallPort).last shouldBe "ok")
      testKit.stop(small)
    }

    "name each robot held safe in doctor (a problem, with its fix), and swap only a simulated robot's battery" in {
      val view = new naogateway.api.GatewayView {
        private def none = scala.concurrent.Future.failed(new UnsupportedOperationException("not asked by doctor"))
        def addresses() = none
        def robots() = none
        def links() = none
        def stats() = none
        def traffic() = none
        def gameState() = none
        def gameSource() = none
      }
      val allWell = Vector(Finding("gateway", "running", problem = false))
      val swapped = new java.util.concurrent.ConcurrentLinkedQueue[Int]()
      val gateway = ControlServer.GatewaySide(
        view,
        () => scala.concurrent.Future.successful(allWell),
        id =>
          if (id == 3) { swapped.add(id); scala.concurrent.Future.successful("robot 3: battery swapped, 12.60 V") }
          else ControlServer.GatewaySide.noSimulatedRobots(id)
      )
      val held = spawn(ControlServer.withInterface(new FleetStub(3), settings, Some(gateway)))
      val doctor = exchange("doctor", address(held).getPort)
      doctor.init shouldBe Vector(
        ". ok   gateway: running",
        ". FAIL safety: robot 3 is held safe, motion refused: battery low: 10.70 V; it clears by itself; fix: swap or " +
          "charge robot 3's battery; the hold ends by itself once it reads full enough (simulated: robotctl battery 3 " +
          "swap)"
      )
      doctor.last shouldBe "error 1 problem(s), each with its fix above"
      exchange("battery 3 swap", address(held).getPort) shouldBe Vector("ok robot 3: battery swapped, 12.60 V")
      exchange("battery 2 swap", address(held).getPort) shouldBe Vector(
        "error robot 2 is not a simulated robot: robotctl battery swaps only the demo's simulated robots' batteries; " +
          "swap a real robot's battery by hand")
      swapped.toArray.toVector shouldBe Vector(3)
      val none = spawn(ControlServer.withInterface(new FleetStub(2), settings, Some(gateway)))
      exchange("doctor", address(none).getPort) shouldBe Vector(". ok   gateway: running",
        ". ok   safety: no robot is held safe", "ok all is well")
      testKit.stop(held)
      testKit.stop(none)
    }

    "end a status with the game, the gate (why it is closed), the message budget, warnings and the game's source" in {
      val reason =
        "the trusted GameController's packet cannot be read: RGme packet of unknown version: bytes from offset 4 are 14 00 00 00"
      val view = new naogateway.api.GatewayView {
        private def none = scala.concurrent.Future.failed(new UnsupportedOperationException("not asked by status"))
        def addresses() = none
        def robots() = none
        def links() = none
        def stats() = none
        def traffic() =
          scala.concurrent.Future.successful(naogateway.api.TrafficStats(0, 0, 125000, Map.empty, 0, 0, 0, 0,
              gameRunning = true, competition = true, gateReason = Some(reason)))
        def gameState() = scala.concurrent.Future.successful(None)
        def gameSource() = scala.concurrent.Future.successful(naogateway.api.GameSource(
            "10.0.0.5/32",
            None,
            0,
            Some("team messages (team 12, UDP 10012): 11990 of 12000 left, 10 counted, 0.2/s"),
            Vector("2 GameControllers on this field: game state from 10.0.0.5:3838 only; " +
              "10.0.0.6:3838 (untrusted, ignored)")
          ))
      }
      val gateway = ControlServer.GatewaySide(view, () => scala.concurrent.Future.successful(Vector.empty))
      val withGateway = spawn(ControlServer.withInterface(new FleetStub(2), settings, Some(gateway)))
      val lines = exchange("status", address(withGateway).getPort)
      lines.takeRight(5) shouldBe Vector(
        ". game: no GameController heard",
        s". competition gate: CLOSED: $reason: nothing is sent to the robots",
        ". team messages (team 12, UDP 10012): 11990 of 12000 left, 10 counted, 0.2/s",
        ". WARNING: 2 GameControllers on this field: game state from 10.0.0.5:3838 only; 10.0.0.6:3838 (untrusted, ignored)",
        "ok game state from nowhere yet (trusted: 10.0.0.5/32)"
      )
      testKit.stop(withGateway)
    }

    "close the interface it owns only, and survive clients that vanish mid-answer" in {
      val socket = connect(port)
      socket.getOutputStream.write("status\n".getBytes(StandardCharsets.UTF_8))
      socket.close()
      exchange("status").last shouldBe "ok"
      fleet.history should not contain "close"
    }
  }
}
