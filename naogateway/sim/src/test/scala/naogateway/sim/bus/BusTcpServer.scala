package naogateway.sim.bus

import java.net.{InetAddress, ServerSocket, Socket}

import scala.util.Try

import naogateway.wire.Dynamixel

/** The emulated bus straight on a loopback TCP port, for tools that test the emulation itself (the DynamixelSDK through
  * socat): one client at a time, packets reassembled as the gateway's bridge does, each run on the bus at the time it
  * arrives (this JVM's clock from the server's start). A test fixture on a thread of its own, not an actor.
  */
final class BusTcpServer(initial: BioloidBus) extends AutoCloseable {
  private val origin = System.nanoTime()
  private val server = new ServerSocket(0, 1, InetAddress.getLoopbackAddress)
  @volatile private var bus = initial
  @volatile private var open = true

  /** The port the bus listens on. */
  val port: Int = server.getLocalPort

  /** The bus as it is now. */
  def current: BioloidBus = synchronized(bus.advance(System.nanoTime() - origin))

  private val thread = new Thread(() => serve(), s"bus-tcp-$port")
  thread.setDaemon(true)
  thread.start()

  private def serve(): Unit =
    while (open)
      Try(server.accept()).foreach(client => Try(talk(client)).fold(_ => client.close(), _ => client.close()))

  private def talk(client: Socket): Unit = {
    val in = client.getInputStream
    val out = client.getOutputStream
    val buffer = new Array[Byte](512)
    var reassembly = Dynamixel.Reassembly()
    var n = in.read(buffer)
    while (n >= 0 && open) {
      val (next, packets) = reassembly.feed(buffer.take(n))
      reassembly = next
      packets.foreach { p =>
        val reply = synchronized {
          val (after, reply) = bus.advance(System.nanoTime() - origin).transact(p)
          bus = after
          reply
        }
        if (reply.nonEmpty) { out.write(reply); out.flush() }
      }
      n = in.read(buffer)
    }
  }

  def close(): Unit = {
    open = false
    server.close()
  }
}
