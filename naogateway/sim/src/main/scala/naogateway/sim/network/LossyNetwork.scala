package naogateway.sim.network

import java.io.IOException
import java.net.{InetAddress, InetSocketAddress}
import java.nio.ByteBuffer
import java.nio.channels.{DatagramChannel, SelectionKey, Selector}
import java.util.concurrent.{ConcurrentLinkedQueue, ExecutionException, TimeUnit, TimeoutException}
import java.util.concurrent.atomic.AtomicInteger

import scala.collection.mutable
import scala.concurrent.duration._
import scala.util.control.NonFatal

import org.slf4j.LoggerFactory

/** A seeded, impaired UDP network on loopback between a gateway and simulated robots.
  *
  * Each proxy stands for one robot host and owns three sockets: the client side P on 127.0.0.1, which the robot sends
  * to; the upstream socket U on the proxy's own host address H (any port), which forwards the robot's datagrams to the
  * gateway, so the gateway sees a host of its own per robot; and the receive side R on H at the robot receive port
  * (3838), where the gateway sends to reach the robot, as it would a real one. Datagrams at R go from P to the robot's
  * receive address (the one given at creation, or the robot receive port on the IP of the robot's latest datagram),
  * never to a source port. Datagrams at U are counted (`atSourcePort`) and dropped, as a robot's module drops them.
  * Each direction passes through [[ImpairmentModel]] with its own [[SeededRandom]] derived from the seed.
  *
  * Design: java.nio with a single thread that owns one `Selector`, every socket and a deadline queue of delayed copies.
  * That thread handles every datagram of every proxy in arrival order, so each direction's decisions come strictly in
  * sequence (which makes them reproducible), delays need no timer per datagram, and any number of proxies costs one
  * thread. Akka IO would add two classic actors per proxy and asynchronous bind/unbind handshakes, and its threads
  * belong to an `ActorSystem`'s dispatchers, so releasing every thread would mean terminating that system; here
  * `stop()` closes every socket and joins the one thread before it returns.
  *
  * Thread safety: every method may be called from any thread. Sockets and state are touched only by the network thread;
  * a method hands it a task and waits for the answer (at most a few seconds), so when it returns its change applies to
  * every later datagram. Methods block briefly, so an actor should not call them from its message handler. After
  * `stop()` every method except `stats`, `stop` and `isRunning` throws `IllegalStateException`.
  */
final class LossyNetwork private (val seed: Long, val name: String) {
  import LossyNetwork._
  import Sockets.{localAddress, openChannel}

  private val selector = Selector.open()
  private val tasks = new ConcurrentLinkedQueue[Task[_]]()
  // Guards the check-then-enqueue of tasks against stop(), so no task is left behind unanswered.
  private val lifecycle = new Object
  @volatile private var accepting = true
  private val thread = new Thread(() => run(), name)
  thread.setDaemon(true)

  // Owned by the network thread, read by others only after it has ended.
  private val proxies = mutable.LongMap.empty[ProxyState]
  private var nextProxyIndex = 0
  private var networkPartitioned = false
  private val pending = mutable.PriorityQueue.empty[PendingCopy](PendingCopy.earliestFirst)
  private var copySequence = 0L
  private val buffer = ByteBuffer.allocate(MaxDatagram)

  /** Starts a proxy on host address `host` that forwards to `gateway`.
    *
    * @param robot
    *   the robot's receive address, where the gateway's datagrams go; `None`: the robot receive port on the IP of the
    *   robot's latest datagram (nothing goes to the robot before its first one)
    * @param receivePort
    *   the robot receive port: where the proxy listens on `host`, and where it delivers when `robot` is not given
    */
  def addProxy(
      gateway: InetSocketAddress,
      host: InetAddress,
      robot: Option[InetSocketAddress] = None,
      uplink: Impairment = Impairment.Off,
      downlink: Impairment = Impairment.Off,
      receivePort: Int = RobotReceivePort
  ): Proxy = {
    require(!gateway.isUnresolved, s"gateway address $gateway is unresolved")
    robot.foreach(r => require(!r.isUnresolved, s"robot address $r is unresolved"))
    onNetworkThread(openProxy(gateway, host, robot, uplink, downlink, receivePort))
  }

  /** Closes a proxy's sockets, forgets copies still waiting, and returns its final stats. */
  def removeProxy(proxy: Proxy): ProxyStats = onNetworkThread {
    val state = stateOf(proxy)
    state.close()
    proxies.remove(proxy.id.toLong)
    // A registered channel keeps its port until the selector drops its key, which happens at the next select.
    selector.selectNow()
    handleSelected()
    state.stats
  }

  /** The settings of one direction of a proxy. */
  def impairment(proxy: Proxy, direction: Direction): Impairment =
    onNetworkThread(stateOf(proxy).link(direction).impairment)

  /** Replaces the settings of one direction of a proxy; they apply from the next datagram on. */
  def setImpairment(proxy: Proxy, direction: Direction, impairment: Impairment): Unit =
    onNetworkThread { stateOf(proxy).link(direction).impairment = impairment }

  /** Switches the partition of both directions of one proxy. */
  def partition(proxy: Proxy, on: Boolean): Unit = onNetworkThread {
    val state = stateOf(proxy)
    Direction.both.foreach { direction =>
      val link = state.link(direction)
      link.impairment = link.impairment.withPartition(on)
    }
  }

  /** Switches a partition of every proxy, both directions, on top of each proxy's own settings. */
  def partitionNetwork(on: Boolean): Unit = onNetworkThread { networkPartitioned = on }

  /** A consistent snapshot of a proxy's stats; after `stop()` the final ones. */
  def stats(proxy: Proxy): ProxyStats =
    tryOnNetworkThread(stateOf(proxy).stats).getOrElse {
      thread.join()
      stateOf(proxy).stats
    }

  /** Whether the network thread still serves requests. */
  def isRunning: Boolean = accepting && thread.isAlive

  /** Closes every socket and ends the network thread; returns once both are done. Calling it again does nothing. */
  def stop(): Unit = {
    lifecycle.synchronized { accepting = false }
    selector.wakeup()
    if (Thread.currentThread() ne thread) thread.join()
  }

  private def start(): Unit = thread.start()

  private def onNetworkThread[A](body: => A): A =
    tryOnNetworkThread(body).getOrElse(throw new IllegalStateException(s"lossy network [$name] is stopped"))

  private def tryOnNetworkThread[A](body: => A): Option[A] =
    if (Thread.currentThread() eq thread) Some(body)
    else {
      val task = new Task(() => body)
      val accepted = lifecycle.synchronized {
        if (accepting) tasks.add(task)
        accepting
      }
      if (!accepted) None
      else {
        selector.wakeup()
        try Some(task.result.get(CallTimeout.toMillis, TimeUnit.MILLISECONDS))
        catch {
          case e: ExecutionException => throw e.getCause
          case _: TimeoutException =>
            throw new IllegalStateException(s"lossy network [$name] did not answer within $CallTimeout")
        }
      }
    }

  private def stateOf(proxy: Proxy): ProxyState =
    proxies.get(proxy.id.toLong).filter(_.handle == proxy).getOrElse {
      throw new IllegalArgumentException(
        s"proxy ${proxy.id} (${proxy.clientSide}) is not part of lossy network [$name]"
      )
    }

  private def openProxy(
      gateway: InetSocketAddress,
      host: InetAddress,
      robot: Option[InetSocketAddress],
      uplink: Impairment,
      downlink: Impairment,
      receivePort: Int
  ): Proxy = {
    val opened = mutable.ArrayBuffer.empty[DatagramChannel]
    try {
      val clientChannel = openChannel(new InetSocketAddress(Loopback, 0))
      opened += clientChannel
      val upstreamChannel = openChannel(new InetSocketAddress(host, 0))
      opened += upstreamChannel
      val receiveChannel = openChannel(new InetSocketAddress(host, receivePort))
      opened += receiveChannel
      val index = nextProxyIndex
      val handle =
        Proxy(index, gateway, localAddress(clientChannel), localAddress(upstreamChannel), localAddress(receiveChannel))
      val state = new ProxyState(
        handle,
        clientChannel,
        upstreamChannel,
        receiveChannel,
        new LinkState(uplink, ImpairmentModel.stream(seed, index, Direction.Uplink)),
        new LinkState(downlink, ImpairmentModel.stream(seed, index, Direction.Downlink)),
        robot,
        receivePort
      )
      clientChannel.register(selector, SelectionKey.OP_READ, Endpoint(state, Direction.Uplink))
      receiveChannel.register(selector, SelectionKey.OP_READ, Endpoint(state, Direction.Downlink))
      upstreamChannel.register(selector, SelectionKey.OP_READ, AtSourcePort(state))
      nextProxyIndex += 1
      proxies.update(index.toLong, state)
      handle
    } catch {
      case NonFatal(e) =>
        opened.foreach(_.close())
        throw e
    }
  }

  private def run(): Unit =
    try {
      while (accepting) {
        runTasks()
        awaitWork()
        handleSelected()
        sendDueCopies()
      }
    } catch {
      case NonFatal(e) => log.error("Lossy network [{}] failed and stops", name, e)
    } finally {
      lifecycle.synchronized { accepting = false }
      closeEverything()
      abandonTasks()
    }

  private def runTasks(): Unit = {
    var task = tasks.poll()
    while (task ne null) {
      task.run()
      task = tasks.poll()
    }
  }

  private def abandonTasks(): Unit = {
    var task = tasks.poll()
    while (task ne null) {
      task.abandon(new IllegalStateException(s"lossy network [$name] is stopped"))
      task = tasks.poll()
    }
  }

  // The earliest deadline bounds the wait, so delayed copies leave on time without polling and an idle network sleeps.
  private def awaitWork(): Unit =
    if (!tasks.isEmpty || !accepting) selector.selectNow()
    else
      pending.headOption match {
        case None => selector.select()
        case Some(copy) =>
          val waitNanos = copy.dueNanos - System.nanoTime()
          if (waitNanos <= 0) selector.selectNow()
          else selector.select(math.max(1L, TimeUnit.NANOSECONDS.toMillis(waitNanos + 999999L)))
      }

  private def handleSelected(): Unit = {
    val keys = selector.selectedKeys().iterator()
    while (keys.hasNext) {
      val key = keys.next()
      keys.remove()
      if (key.isValid && key.isReadable) key.attachment() match {
        case Endpoint(state, direction) => readFrom(state, direction)
        case AtSourcePort(state)        => drainSourcePort(state)
        case _                          => ()
      }
    }
  }

  // Reads a bounded batch so one flooded socket cannot starve the others or the delayed copies.
  private def readFrom(state: ProxyState, direction: Direction): Unit = {
    val channel = state.receivingChannel(direction)
    var remaining = MaxReadsPerWakeup
    while (remaining > 0 && state.open) {
      buffer.clear()
      val source =
        try channel.receive(buffer)
        catch {
          case e: IOException =>
            log.debug("Proxy [{}] could not read its {} socket", Int.box(state.handle.id), direction, e)
            null
        }
      source match {
        case from: InetSocketAddress =>
          buffer.flip()
          val bytes = new Array[Byte](buffer.remaining())
          buffer.get(bytes)
          handleDatagram(state, direction, from, bytes)
          remaining -= 1
        case _ => remaining = 0
      }
    }
  }

  // The gateway sent to the port the robot's datagrams came from: a robot's client connection passes nothing on.
  private def drainSourcePort(state: ProxyState): Unit = {
    var remaining = MaxReadsPerWakeup
    while (remaining > 0 && state.open) {
      buffer.clear()
      val source =
        try state.upstreamChannel.receive(buffer)
        catch { case _: IOException => null }
      if (source == null) remaining = 0
      else {
        state.link(Direction.Downlink).atSourcePort += 1
        remaining -= 1
      }
    }
  }

  private def handleDatagram(
      state: ProxyState,
      direction: Direction,
      from: InetSocketAddress,
      bytes: Array[Byte]
  ): Unit = {
    val link = state.link(direction)
    link.received += 1
    val target = direction match {
      case Direction.Uplink =>
        // Where the robot receives: its IP at the receive port, whatever port this datagram left from.
        if (state.fixedRobot.isEmpty) state.robot = Some(new InetSocketAddress(from.getAddress, state.receivePort))
        Some(state.handle.gateway)
      case Direction.Downlink => state.robot
    }
    target match {
      case None => link.undeliverable += 1
      case Some(to) =>
        val settings =
          if (networkPartitioned && !link.impairment.partitioned) link.impairment.withPartition(true)
          else link.impairment
        val (decision, next) = ImpairmentModel.decide(settings, link.rng)
        link.rng = next
        decision match {
          case Decision.Drop(DropCause.Loss)      => link.droppedLoss += 1
          case Decision.Drop(DropCause.Partition) => link.droppedPartition += 1
          case deliver: Decision.Deliver =>
            link.forwarded += 1
            if (deliver.duplicated) link.duplicated += 1
            if (deliver.reordered) link.reordered += 1
            val now = System.nanoTime()
            deliver.delays.foreach { delay =>
              if (delay == Duration.Zero) transmit(state, direction, bytes, to)
              else {
                pending.enqueue(PendingCopy(now + delay.toNanos, copySequence, state, direction, bytes, to))
                copySequence += 1
              }
            }
        }
    }
  }

  private def sendDueCopies(): Unit = {
    val now = System.nanoTime()
    while (pending.nonEmpty && pending.head.dueNanos - now <= 0) {
      val copy = pending.dequeue()
      if (copy.state.open) transmit(copy.state, copy.direction, copy.bytes, copy.to)
    }
  }

  private def transmit(state: ProxyState, direction: Direction, bytes: Array[Byte], to: InetSocketAddress): Unit = {
    val link = state.link(direction)
    try {
      if (state.sendingChannel(direction).send(ByteBuffer.wrap(bytes), to) == 0) link.sendFailures += 1
    } catch {
      case e: IOException =>
        link.sendFailures += 1
        log.debug("Proxy [{}] could not send {} to {}", Int.box(state.handle.id), direction, to, e)
    }
  }

  private def closeEverything(): Unit = {
    proxies.valuesIterator.foreach(_.close())
    pending.clear()
    // Closing the selector drops every key, which is what finally releases the channels' ports.
    try selector.close()
    catch { case e: IOException => log.warn("Lossy network [{}] could not close its selector", name, e) }
  }
}

/** Starting a [[LossyNetwork]]. */
object LossyNetwork {
  private val log = LoggerFactory.getLogger(classOf[LossyNetwork])
  private val instances = new AtomicInteger(0)

  private val Loopback = InetAddress.getLoopbackAddress

  /** The port a robot receives on (docs/protocol.md section 2). */
  val RobotReceivePort: Int = 3838
  private val MaxDatagram = 65536
  private val MaxReadsPerWakeup = 64
  private val CallTimeout = 5.seconds

  /** Starts a network with no proxies; `seed` determines every random decision of every proxy. */
  def start(seed: Long): LossyNetwork = {
    val network = new LossyNetwork(seed, s"lossy-network-${instances.incrementAndGet()}")
    network.start()
    network
  }

}
