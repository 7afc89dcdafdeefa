package firmware

import java.io.InputStream
import java.net.{DatagramPacket, DatagramSocket, InetSocketAddress, Socket, SocketTimeoutException}
import java.nio.charset.StandardCharsets

import scala.collection.immutable.ArraySeq
import scala.concurrent.duration._
import scala.jdk.CollectionConverters._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.sim.gs1500m.{Gs1500mSerial, Remote, SerialDecoder, SerialEvent}
import naogateway.testkit.TestLoopback

/** The host's GS1500M ([[Gs1500mBridge]]) without qemu: this spec plays the CM-530 on the serial socket itself, so the
  * module's side of docs/protocol.md section 12 is checked on every machine, tools or not.
  */
class Gs1500mBridgeSpec extends AnyWordSpec with Matchers {

  private val BaseStation = Remote("192.168.1.10", 11011)

  /** The CM-530's end of the serial line: what it writes, and the module's items it reads back. */
  private final class Firmware(port: Int) {
    val socket = new Socket("127.0.0.1", port)
    socket.setSoTimeout(50)
    private val in: InputStream = socket.getInputStream
    private var decoder = SerialDecoder.empty
    private var pending = Vector.empty[SerialEvent]

    def write(bytes: Array[Byte]): Unit = { socket.getOutputStream.write(bytes); socket.getOutputStream.flush() }
    def line(text: String): Unit = write((text + "\r\n").getBytes(StandardCharsets.US_ASCII))

    /** The next item the module sends that `pf` takes, skipping the others; fails after `within`. */
    def next[T](within: FiniteDuration = 3.seconds)(pf: PartialFunction[SerialEvent, T]): T = {
      val deadline = within.fromNow
      val buffer = new Array[Byte](4096)
      while (deadline.hasTimeLeft()) {
        pending.indexWhere(pf.isDefinedAt) match {
          case -1 =>
            pending = Vector.empty
            val n =
              try in.read(buffer)
              catch { case _: SocketTimeoutException => 0 }
            if (n > 0) {
              val (d, events) = decoder.feed(java.util.Arrays.copyOf(buffer, n))
              decoder = d
              pending = events
            }
          case i =>
            val found = pending(i)
            pending = pending.drop(i + 1)
            return pf(found)
        }
      }
      fail(s"the module sent nothing expected within $within")
    }

    /** Sends `command` and returns the connection id of its `CONNECT`, after its `OK`. */
    def connect(command: String): Int = {
      line(command)
      val cid = next() { case SerialEvent.StatusLine(s"CONNECT $c") => Integer.parseInt(c, 16) }
      next() { case SerialEvent.StatusLine("OK") => () }
      cid
    }
  }

  private def receive(socket: DatagramSocket): (Array[Byte], InetSocketAddress) = {
    val buffer = new Array[Byte](2048)
    val packet = new DatagramPacket(buffer, buffer.length)
    socket.setSoTimeout(3000)
    socket.receive(packet)
    java.util.Arrays.copyOf(buffer, packet.getLength) -> packet.getSocketAddress.asInstanceOf[InetSocketAddress]
  }

  "The host's GS1500M" should {
    "be silent while it boots, then answer AT commands, open connections and carry datagrams both ways" in {
      val robot = TestLoopback.address()
      val base = new DatagramSocket(new InetSocketAddress("127.0.0.1", 0))
      val bridge = new Gs1500mBridge(Gs1500mBridge.Config(robot,
          hosts = Map(BaseStation -> base.getLocalSocketAddress.asInstanceOf[InetSocketAddress]),
          bootDelay = 300.millis))
      val fw = new Firmware(bridge.serialPort)
      try {
        // During its boot the module hears nothing.
        fw.line("AT")
        Thread.sleep(100)
        bridge.commands.asScala shouldBe empty
        fw.next() { case SerialEvent.StatusLine("Serial2WiFi APP") => () }
        // Echo until ATE0, then plain answers.
        fw.line("AT")
        fw.next() { case SerialEvent.StatusLine("AT") => () }
        fw.next() { case SerialEvent.StatusLine("OK") => () }
        fw.line("ATE0")
        fw.next() { case SerialEvent.StatusLine("OK") => () }
        fw.line("AT+BDATA=1")
        fw.next() { case e: SerialEvent.StatusLine => e.text } shouldBe "OK"
        fw.line("AT+FOO")
        fw.next() { case SerialEvent.StatusLine(t) => t } shouldBe "ERROR: INVALID INPUT"
        val client = fw.connect("AT+NCUDP=192.168.1.10,11011")
        val server = fw.connect("AT+NSUDP=3838")
        client should not be server

        // ESC Z on the client: one datagram to the base station, from the robot's own address; then ESC O.
        val status = ArraySeq.from("hello base".getBytes(StandardCharsets.US_ASCII))
        fw.write(Gs1500mSerial.encodeBulk(client, status).toOption.get.toArray)
        val (got, from) = receive(base)
        got.toSeq shouldBe status
        from.getAddress shouldBe robot
        fw.next() { case SerialEvent.Ack => () }

        // A datagram to the robot's 3838 comes as ESC y, its sender under the base station's network name.
        val reply = "from the gateway".getBytes(StandardCharsets.US_ASCII)
        base.send(new DatagramPacket(reply, reply.length, new InetSocketAddress(robot, 3838)))
        fw.next() { case SerialEvent.Data(`server`, Some(r), bytes) =>
          (r, bytes.toSeq)
        } shouldBe
          (BaseStation -> reply.toSeq)
        // The base station answering the client's port comes back as ESC Z on the client's connection.
        base.send(new DatagramPacket(reply, reply.length, from))
        fw.next() { case SerialEvent.Data(`client`, None, bytes) => bytes.toSeq } shouldBe reply.toSeq

        // Over 1400 bytes: the module never takes it (the model counts it lost, nothing reaches the firmware).
        val big = new Array[Byte](1401)
        base.send(new DatagramPacket(big, big.length, new InetSocketAddress(robot, 3838)))
        val deadline = 3.seconds.fromNow
        while (bridge.stats.lostOversize == 0 && deadline.hasTimeLeft()) Thread.sleep(20)
        bridge.stats.lostOversize shouldBe 1

        // Garbage from the firmware is counted, and the line still works.
        fw.write(Array[Byte](0x01, 0x02, 0x03, '\n'))
        fw.write(Gs1500mSerial.encodeBulk(client, status).toOption.get.toArray)
        receive(base)._1.toSeq shouldBe status
        bridge.firmwareGarbage should be > 0L

        // Losing the network: DISASSOCIATED, then silence; afterwards a new start-up works.
        bridge.disassociate(rejoinAfter = 300.millis)
        fw.next() { case SerialEvent.StatusLine("DISASSOCIATED") => () }
        fw.line("AT")
        Thread.sleep(100)
        bridge.commands.asScala.count(_ == "AT") shouldBe 1
        Thread.sleep(300)
        fw.line("AT")
        fw.next() { case SerialEvent.StatusLine("OK") => () }
        fw.connect("AT+NCUDP=192.168.1.10,11011") shouldBe 0
      } finally {
        fw.socket.close()
        bridge.close()
        base.close()
      }
    }
  }
}
