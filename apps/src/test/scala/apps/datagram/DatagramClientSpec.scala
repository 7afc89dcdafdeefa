package apps.datagram

import java.io.File
import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.DatagramChannel

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import com.typesafe.config.ConfigFactory
import org.scalatest.wordspec.AnyWordSpecLike

import apps.zeromq.{EndpointProtocol, PythonEnv, StubRobots}

/** The Python client's datagram transport (`DatagramGatewayClient`) against the datagram door and a silent socket. */
class DatagramClientSpec
    extends ScalaTestWithActorTestKit(ConfigFactory.parseString("apps.datagram-door.port = 0")
        .withFallback(ConfigFactory.load()))
    with AnyWordSpecLike
    with LogCapturing {

  "DatagramGatewayClient" must {
    "call through the door, report refusals and timeouts, and send only what changes nothing again" in {
      val python = PythonEnv.python() // cancels here when Python is missing, before anything is started
      val stub = new StubRobots(system)
      val door = spawn(DatagramDoor.withInterface(stub, DatagramDoorSettings(system)))
      val probe = createTestProbe[InetSocketAddress]()
      door ! DatagramDoor.GetAddress(probe.ref)
      val address = probe.receiveMessage(5.seconds)
      // Nothing answers here: what the client sends is counted.
      val silent = DatagramChannel.open().bind(new InetSocketAddress("127.0.0.1", 0))
      try {
        val silentPort = silent.getLocalAddress.asInstanceOf[InetSocketAddress].getPort
        val code =
          s"""from naogateway_client import DatagramGatewayClient, GatewayError
             |c = DatagramGatewayClient("127.0.0.1:${address.getPort}", timeout=5.0)
             |print("robots:", c.robots())
             |print("say:", c.say(7, "hi"))
             |s = c.status(7)
             |print("status:", s["online"], round(s["battery"], 2))
             |try:
             |    c.stop(8)
             |except GatewayError as e:
             |    print("refused:", e.category)
             |c.close()
             |q = DatagramGatewayClient(("127.0.0.1", ${address.getPort}), timeout=0.5)
             |try:
             |    q.stop(14)
             |except GatewayError as e:
             |    print("unanswered:", e.category)
             |q.close()
             |n = DatagramGatewayClient("127.0.0.1:$silentPort", timeout=1.0, retries=2, retry_interval=0.2)
             |for name, f in (("robots", n.robots), ("walk", lambda: n.walk(7, 0.1, 0.0, 0.0))):
             |    try:
             |        f()
             |    except GatewayError as e:
             |        print(name + ":", e.category)
             |n.close()
             |""".stripMargin
        val (exit, output) = PythonEnv.run(
          Seq(python.getPath, "-u", "-c", code),
          60.seconds,
          new File(PythonEnv.root, "apps/target/datagram-client.log"),
          Map(
            "NAOGATEWAY_PY_GEN" -> new File(PythonEnv.root, "apps/target/python-gen").getPath,
            "PYTHONPATH" -> new File(PythonEnv.root, "apps/python").getPath,
            "PYTHONDONTWRITEBYTECODE" -> "1"
          )
        )
        withClue(output) {
          exit shouldBe 0
          output.linesIterator.toVector shouldBe Vector(
            "robots: [7, 8]",
            "say: True",
            "status: True 12.3",
            "refused: offline",
            "unanswered: timeout",
            "robots: timeout",
            "walk: timeout"
          )
        }
        // The unanswered stop reached the robots once: a call is never sent again.
        stub.seen.count(_ == "stop 14") shouldBe 1
        silent.configureBlocking(false)
        val buffer = ByteBuffer.allocate(65536)
        val heard = Iterator.continually {
          buffer.clear()
          Option(silent.receive(buffer)).map { _ =>
            buffer.flip()
            val bytes = new Array[Byte](buffer.remaining)
            buffer.get(bytes)
            EndpointProtocol.parse(bytes).fold(u => fail(u.error), _.call.name)
          }
        }.takeWhile(_.isDefined).flatten.toVector
        heard shouldBe Vector.fill(3)("gateway.robots") :+ "motion.walk"
      } finally {
        silent.close()
        testKit.stop(door)
      }
    }
  }
}
