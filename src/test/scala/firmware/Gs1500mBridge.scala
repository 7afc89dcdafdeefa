package firmware

import java.io.{File, InputStream, OutputStream}
import java.net.{
  DatagramPacket,
  DatagramSocket,
  InetAddress,
  InetSocketAddress,
  ServerSocket,
  Socket,
  SocketException,
  SocketTimeoutException
}
import java.nio.charset.StandardCharsets
import java.util.concurrent.{ConcurrentLinkedQueue, TimeUnit}
import java.util.concurrent.atomic.{AtomicBoolean, AtomicLong, AtomicReference}

import scala.collection.immutable.ArraySeq
import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.util.Try

import naogateway.sim.gs1500m.{
  AirDatagram,
  Gs1500mConfig,
  Gs1500mModule,
  Gs1500mStats,
  ModuleEvent,
  ModuleStep,
  Remote,
  SerialDecoder,
  SerialEvent
}

/** The robot's GS1500M WiFi module on the host, for a firmware image in qemu: qemu connects the board's UART5 (its
  * fifth `-serial`) to [[serialPort]], and the bridge plays the module at the other end of that line, as
  * docs/protocol.md section 12 describes it and the simulator models it:
  *
  *   - after power-up it is silent for `bootDelay`, prints its banner, then answers AT commands (echoing them until
  *     `ATE0`): `AT`, `ATE0`, `AT+BDATA=1`, `AT+NCUDP=<ip>,<port>` (a UDP client: `CONNECT <cid>`), `AT+NSUDP=<port>`
  *     (a UDP server), `AT+NCLOSE=<cid>`; anything else gets `ERROR: INVALID INPUT`;
  *   - `ESC Z <cid> <len4> <data>` from the firmware goes out as one UDP datagram from a socket of the robot's own
  *     loopback address (a client connection's own port; the server's is `robotAddress:port`);
  *   - datagrams arriving at the server come to the firmware as `ESC y <cid> <ip> <port> TAB <len4> <data>`, at a
  *     client connection as `ESC Z`, with `ESC O` after each packet the module sent;
  *   - the module's one 1400-byte buffer, shared by both directions and emptied at the serial line's rate, is the
  *     simulator's [[Gs1500mModule]]: what does not fit is lost or overwritten as the thesis observed (6.1).
  *
  * The firmware names hosts as a robot on a real network would (the base station at 192.168.1.10:11011); `hosts` says
  * where each is on the host (the gateway's loopback address), and the bridge translates both ways, as a NAT would: a
  * destination is looked up by address and port, then by address alone (the port kept); a sender on the host is
  * reported under its network name the same way. So the firmware sees one consistent network, answers the gateway at
  * the address it knows, and accepts its stream segments. The serial stream from the firmware is read with the
  * simulator's [[SerialDecoder]] (AT commands are its text lines, bulk data its `ESC Z` items). Everything runs on the
  * bridge's own threads, each ending when [[close]] is called.
  */
final class Gs1500mBridge(config: Gs1500mBridge.Config) extends AutoCloseable {
  import Gs1500mBridge._

  private val server = new ServerSocket(0, 1, InetAddress.getLoopbackAddress)
  server.setSoTimeout(200)

  /** The TCP port qemu's `-serial tcp:127.0.0.1:PORT,nodelay=on` connects to. */
  val serialPort: Int = server.getLocalPort

  private val closed = new AtomicBoolean(false)
  private val inbound = new ConcurrentLinkedQueue[AirDatagram]()
  private val requests = new ConcurrentLinkedQueue[Request]()
  private val connected = new AtomicBoolean(false)

  /** Every AT command the firmware sent, in order. */
  val commands = new ConcurrentLinkedQueue[String]()

  /** Every datagram that went on air: connection, destination on the host, bytes. */
  val sent = new ConcurrentLinkedQueue[Sent]()

  private val moduleStats = new AtomicReference(Gs1500mStats())
  private val garbageFromFirmware = new AtomicLong()
  private val lostInbound = new AtomicLong()

  /** The module model's counters (losses, overwrites, peak buffer use). */
  def stats: Gs1500mStats = moduleStats.get

  /** Bytes from the firmware that were neither a command nor bulk data. */
  def firmwareGarbage: Long = garbageFromFirmware.get

  /** Whether qemu has connected its serial port. */
  def isConnected: Boolean = connected.get

  /** Datagrams that arrived for a connection the module no longer had. */
  def arrivalsWithoutConnection: Long = lostInbound.get

  /** The module loses the network: `DISASSOCIATED`, every connection gone, silent for `rejoinAfter`. */
  def disassociate(rejoinAfter: FiniteDuration): Unit = requests.add(Disassociate(rejoinAfter))

  private val thread = new Thread(() => run(), "gs1500m-bridge")
  thread.setDaemon(true)
  thread.start()

  override def close(): Unit =
    if (closed.compareAndSet(false, true)) {
      Try(server.close())
      thread.join(5000)
    }

  // ---- the module thread: the serial line, the buffer model and every connection's socket -----------------------

  private final class Connection(val cid: Int, val socket: DatagramSocket, val destination: Option[InetSocketAddress]) {
    private val reader = new Thread(() => receive(), s"gs1500m-bridge-cid-$cid")
    reader.setDaemon(true)
    reader.start()

    private def receive(): Unit = {
      val buffer = new Array[Byte](65536)
      while (!socket.isClosed && !closed.get) {
        val packet = new DatagramPacket(buffer, buffer.length)
        try {
          socket.receive(packet)
          val from = packet.getSocketAddress.asInstanceOf[InetSocketAddress]
          val remote = if (destination.isEmpty) Some(config.nameOf(from)) else None
          inbound.add(AirDatagram(cid, remote,
              ArraySeq.unsafeWrapArray(java.util.Arrays.copyOf(buffer, packet.getLength))))
        } catch {
          case _: SocketTimeoutException => ()
          case _: SocketException        => ()
        }
      }
    }

    def close(): Unit = { socket.close(); reader.join(2000) }
  }

  private def run(): Unit = {
    var socket: Socket = null
    while (socket == null && !closed.get)
      socket =
        try server.accept()
        catch { case _: SocketTimeoutException => null; case _: SocketException => null }
    if (socket != null) {
      connected.set(true)
      socket.setTcpNoDelay(true)
      socket.setSoTimeout(1)
      try new Module(socket.getInputStream, socket.getOutputStream).loop()
      catch { case _: SocketException => () } // qemu ended
      finally Try(socket.close())
    }
  }

  private final class Module(in: InputStream, out: OutputStream) {
    private val started = System.nanoTime()
    private def now: Long = System.nanoTime() - started
    private var model = Gs1500mModule(config.module, seed = config.seed, start = 0L)
    private var decoder = SerialDecoder.empty
    private var echo = true
    private var bannerDone = false
    private var silentUntil = config.bootDelay.toNanos
    private val connections = scala.collection.mutable.Map.empty[Int, Connection]
    private var lineFreeAt = 0L

    def loop(): Unit = {
      val buffer = new Array[Byte](4096)
      try while (!closed.get) {
          val n =
            try in.read(buffer)
            catch { case _: SocketTimeoutException => 0 }
          if (n < 0) return
          if (n > 0) {
            val (next, events) = decoder.feed(java.util.Arrays.copyOf(buffer, n))
            decoder = next
            events.foreach(fromFirmware)
          }
          Iterator.continually(requests.poll()).takeWhile(_ != null).foreach {
            case Disassociate(rejoin) =>
              connections.values.foreach(_.close())
              connections.clear()
              status("DISASSOCIATED")
              silentUntil = now + rejoin.toNanos
          }
          Iterator.continually(inbound.poll()).takeWhile(_ != null).foreach { d =>
            if (connections.contains(d.cid)) step(model.arrive(d, now)) else lostInbound.incrementAndGet()
          }
          step(model.advance(now))
          if (!bannerDone && now >= silentUntil) { bannerDone = true; status("Serial2WiFi APP") }
          toFirmware()
        }
      finally {
        connections.values.foreach(_.close())
      }
    }

    private def step(s: ModuleStep): Unit = {
      model = s.module
      moduleStats.set(model.stats)
      onAir(s.events)
    }

    // Every call into the model advances its clock, so any of them may complete a packet's transfer: each step's
    // events go through here, or a packet the model counted on air never leaves.
    private def onAir(events: Vector[ModuleEvent]): Unit =
      events.foreach {
        case ModuleEvent.OnAir(cid, data, _) =>
          connections.get(cid).foreach { c =>
            c.destination.foreach { to =>
              Try(c.socket.send(new DatagramPacket(data.toArray, data.length, to)))
              sent.add(Sent(cid, to, data))
            }
          }
        case _ => ()
      }

    // The serial line towards the firmware: everything queued, once the line is free (the model drains it at
    // the line's rate and frees the buffer as it goes).
    private def toFirmware(): Unit = {
      val t = now
      if (t >= lineFreeAt) {
        val read = model.firmwareRead(t)
        model = read.module
        moduleStats.set(model.stats)
        onAir(read.events)
        if (read.bytes.nonEmpty) {
          out.write(read.bytes.toArray)
          out.flush()
          lineFreeAt = read.doneAt
        }
      }
    }

    private def status(text: String): Unit = step(model.statusLine(text, now))

    private def fromFirmware(event: SerialEvent): Unit = event match {
      case SerialEvent.StatusLine(text) =>
        if (now >= silentUntil) {
          commands.add(text)
          if (echo) status(text)
          command(text.trim)
        }
      case SerialEvent.Data(cid, None, bytes) => step(model.firmwareSend(cid, bytes, now))
      case SerialEvent.Garbage(count)         => garbageFromFirmware.addAndGet(count.toLong)
      case _                                  => garbageFromFirmware.incrementAndGet()
    }

    private val Client = """AT\+NCUDP=(\d{1,3}(?:\.\d{1,3}){3}),(\d{1,5})(?:,\d{1,5})?""".r
    private val UdpServer = """AT\+NSUDP=(\d{1,5})""".r
    private val Close = """AT\+NCLOSE=([0-9a-fA-F])""".r

    private def command(text: String): Unit = text match {
      case "AT" | "AT+BDATA=1" => status("OK")
      case "ATE0"              => echo = false; status("OK")
      case "ATE1"              => echo = true; status("OK")
      case Client(ip, port) if port.toInt <= 65535 =>
        open(bound(config.robotAddress, 0),
          Some(config.addressOf(Remote(ip, port.toInt))))
      case UdpServer(port) if port.toInt <= 65535 =>
        open(bound(config.robotAddress, port.toInt), None)
      case Close(cid) =>
        connections.remove(Integer.parseInt(cid, 16)) match {
          case Some(c) => c.close(); status("OK")
          case None    => status("ERROR: INVALID CID")
        }
      case _ => status("ERROR: INVALID INPUT")
    }

    // With SO_REUSEADDR, as the gateway's GameController listener has it: a process elsewhere on this machine holding
    // the wildcard address at 3838 must not keep the robot from its own address (the more specific bind gets the
    // robot's datagrams).
    private def bound(address: InetAddress, port: Int): Option[DatagramSocket] = Try {
      val s = new DatagramSocket(null: java.net.SocketAddress)
      s.setReuseAddress(true)
      Try(s.bind(new InetSocketAddress(address, port))).fold(e => { s.close(); throw e }, _ => s)
    }.toOption

    private def open(socket: Option[DatagramSocket], destination: Option[InetSocketAddress]): Unit =
      (socket, (0 to 15).find(c => !connections.contains(c))) match {
        case (Some(s), Some(cid)) =>
          s.setSoTimeout(100)
          connections(cid) = new Connection(cid, s, destination)
          status(s"CONNECT ${Integer.toHexString(cid)}")
          status("OK")
        case (s, _) =>
          s.foreach(_.close())
          status("ERROR")
      }
  }
}

/** Settings, records and qemu itself. */
object Gs1500mBridge {

  /** @param robotAddress
    *   the robot's own loopback address: its UDP server listens there, its clients send from there
    * @param hosts
    *   network name (as the firmware knows it) to where that host is on this machine
    * @param module
    *   the module's buffer and serial line, as the simulator models them
    * @param bootDelay
    *   silence after power-up (the real module: about 4 s; the board image waits less)
    * @param seed
    *   the buffer model's overflow coin
    */
  final case class Config(
      robotAddress: InetAddress,
      hosts: Map[Remote, InetSocketAddress] = Map.empty,
      module: Gs1500mConfig = Gs1500mConfig(),
      bootDelay: FiniteDuration = 300.millis,
      seed: Long = 1L
  ) {

    /** Where a destination the firmware names is: its host by address and port, else by address (port kept), else where
      * it says.
      */
    def addressOf(r: Remote): InetSocketAddress =
      hosts.get(r).orElse(
        hosts.collectFirst { case (n, a) if n.ip == r.ip => new InetSocketAddress(a.getAddress, r.port) })
        .getOrElse(new InetSocketAddress(r.ip, r.port))

    /** How the firmware sees a sender on this machine: the reverse of [[addressOf]]. */
    def nameOf(a: InetSocketAddress): Remote =
      hosts.collectFirst { case (n, h) if h == a => n }
        .orElse(hosts.collectFirst { case (n, h) if h.getAddress == a.getAddress => Remote(n.ip, a.getPort) })
        .getOrElse(Remote(a.getAddress.getHostAddress, a.getPort))
  }

  /** A datagram the module sent on air. */
  final case class Sent(cid: Int, to: InetSocketAddress, bytes: ArraySeq[Byte])

  private sealed trait Request
  private final case class Disassociate(rejoinAfter: FiniteDuration) extends Request
}

/** qemu's `netduino2` as the robot's board: the image's UART5 on the bridge's serial port, its USART1 (the Dynamixel
  * bus, port/qemu/bus_qemu.c) on a bus model's TCP port when there is one, its semihosting output in a log file, its
  * arguments through `-append`.
  */
object QemuBoard {

  /** The qemu binary. */
  val Binary = "qemu-system-arm"

  /** Starts `elf`; `serialPort` is the bridge's (None: the UART goes nowhere); `busPort` is the bus model's (the
    * standalone busmodel, firmware/tools/busmodel_main.c; None: no bus, the body stays off); `icountShift` makes
    * instruction counting deterministic (`-icount shift=N,sleep=off`).
    */
  def start(elf: File, log: File, arguments: Seq[String] = Nil, serialPort: Option[Int] = None,
      icountShift: Option[Int] = None, busPort: Option[Int] = None): Process = {
    val uart5 = serialPort.fold("null")(p => s"tcp:127.0.0.1:$p,nodelay=on")
    val usart1 = busPort.fold("null")(p => s"tcp:127.0.0.1:$p,nodelay=on")
    val command = Seq(
      Binary,
      "-M",
      "netduino2",
      "-display",
      "none",
      "-monitor",
      "none",
      "-nodefaults",
      "-serial",
      usart1,
      "-serial",
      "null",
      "-serial",
      "null",
      "-serial",
      "null",
      "-serial",
      uart5,
      "-semihosting-config",
      "enable=on,target=native",
      "-kernel",
      elf.getPath
    ) ++
      icountShift.toSeq.flatMap(s => Seq("-icount", s"shift=$s,sleep=off")) ++
      (if (arguments.nonEmpty) Seq("-append", arguments.mkString(" ")) else Nil)
    new ProcessBuilder(command.asJava).redirectErrorStream(true).redirectOutput(log).start()
  }

  /** Waits for `process` to end by itself within `within`, else ends it; its exit status (None: it was ended). */
  def await(process: Process, within: FiniteDuration): Option[Int] =
    if (process.waitFor(within.toMillis, TimeUnit.MILLISECONDS)) Some(process.exitValue())
    else { stop(process); None }

  /** Ends `process` (this one process, nothing else). */
  def stop(process: Process): Unit = {
    process.destroy()
    if (!process.waitFor(5, TimeUnit.SECONDS)) process.destroyForcibly()
  }

  /** The log's text so far. */
  def output(log: File): String =
    Try(new String(java.nio.file.Files.readAllBytes(log.toPath), StandardCharsets.UTF_8)).getOrElse("")
}
