package naogateway.testkit

import java.net.{DatagramSocket, InetAddress, InetSocketAddress}

import scala.util.Try

/** Loopback addresses of their own for simulated robots and proxies in tests: Linux routes all of 127.0.0.0/8 to the
  * loopback interface, so each robot can receive on its own 127.a.b.c at UDP 3838, as a real robot does on its own IP.
  *
  * Every address is handed out once per test JVM. The JVMs of one build run side by side (one per module), so each
  * takes its block from its process id (127.<1 + pid mod 250>.x.y), and an address whose port is taken at the moment of
  * allocation (another JVM, an earlier run's leftover) is skipped. 127.0.0.x is never used: the demo and the
  * conformance robot live there.
  */
object TestLoopback {

  /** The port a robot receives on (docs/protocol.md section 2); on a robot's own address it is free to use. */
  val RobotReceivePort: Int = 3838

  private val block: Int = 1 + (ProcessHandle.current().pid() % 250).toInt
  // The next unused index of this JVM's block; index i is 127.<block>.<1 + i / 254>.<1 + i % 254>.
  private var next = 0

  /** A fresh loopback address whose `port` (the robot receive port by default) is free now. */
  def address(port: Int = RobotReceivePort): InetAddress = block(1, port)

  /** `n` fresh consecutive loopback addresses (for a fleet: robot `i` at the first + `i`), each with `port` free now;
    * returns the first.
    */
  def block(n: Int, port: Int = RobotReceivePort): InetAddress = synchronized {
    require(n >= 1 && n <= 200 * 254, s"a block holds 1 to ${200 * 254} addresses, not $n")
    Iterator.continually {
      val first =
        if (n <= 254) {
          // Within one third octet, so first + i is the allocator's own index + i.
          if (next % 254 + n > 254) next = (next / 254 + 1) * 254
          next
        } else {
          // Whole third octets from here: first + i runs through .255 and .0 too.
          next = (next / 254 + 1) * 254
          next
        }
      val hosts = (0 until n).map(i => plus(host(first), i))
      next = if (n <= 254) first + n else first + ((n + 1) / 256 + 2) * 254
      hosts
    }.find(_.forall(free(_, port))).get.head
  }

  private def plus(address: InetAddress, i: Int): InetAddress =
    InetAddress.getByAddress(
      java.nio.ByteBuffer.allocate(4).putInt(java.nio.ByteBuffer.wrap(address.getAddress).getInt + i).array())

  /** A fresh address at the robot receive port, as a socket address. */
  def robotAt(port: Int = RobotReceivePort): InetSocketAddress = new InetSocketAddress(address(port), port)

  // .0 and .255 are skipped so no address looks like a network or broadcast one.
  private def host(index: Int): InetAddress = {
    require(index < 254 * 254, "the test JVM used every loopback address of its block")
    InetAddress.getByAddress(Array[Byte](127, block.toByte, (index / 254 + 1).toByte, (index % 254 + 1).toByte))
  }

  private def free(address: InetAddress, port: Int): Boolean =
    Try(new DatagramSocket(new InetSocketAddress(address, port)).close()).isSuccess
}
