package naogateway.gateway.link

import java.net.InetSocketAddress

import akka.actor.typed.scaladsl.Behaviors
import akka.actor.typed.scaladsl.adapter._
import akka.actor.typed.{ActorRef, Behavior}
import akka.io.{IO, Inet, Udp}
import akka.util.ByteString
import akka.{actor => classic}

/** One UDP socket on Akka IO: datagrams in go to the owner, datagrams out come from anyone with the ref. */
object UdpLink {

  /** What a link accepts. */
  sealed trait Command

  /** Sends `bytes` to `to`; the bytes are not copied, so the caller must not change them afterwards. */
  final case class Send(bytes: Array[Byte], to: InetSocketAddress) extends Command

  /** Closes the socket; the link stops once it is closed. */
  case object Unbind extends Command

  private final case class SocketReady(socket: classic.ActorRef, local: InetSocketAddress) extends Command
  private final case class SocketFailed(reason: String) extends Command
  private final case class SocketReceived(data: ByteString, from: InetSocketAddress) extends Command
  private case object SocketClosed extends Command

  /** What a link tells its owner. */
  sealed trait Event

  /** The socket is bound at `local` (the real port when 0 was asked for). */
  final case class Bound(link: ActorRef[Command], local: InetSocketAddress) extends Event

  /** Binding failed, e.g. the port is taken. */
  final case class BindFailed(address: InetSocketAddress, reason: String) extends Event

  /** A datagram arrived. */
  final case class Received(bytes: Array[Byte], from: InetSocketAddress) extends Event

  /** `count` datagrams arrived over the link's cap in a second that has ended and were dropped unread; `lastFrom` sent
    * the last of them. Told with the first datagram after that second, so a flood costs the owner at most one message a
    * second beside the datagrams within the cap.
    */
  final case class Dropped(count: Long, lastFrom: InetSocketAddress, trusted: Boolean = false) extends Event

  /** Options a link binds with. `maxDatagramsPerSecond` (0: no cap) bounds what the owner is handed, so a flood on a
    * port anyone can send to (the GameController's, the team's) cannot grow the owner's mailbox without bound.
    * Datagrams from addresses `trusted` holds are sorted out before the cap and counted against a cap of their own, so
    * a flood from anyone else cannot crowd them out (a `Dropped` of theirs says `trusted`).
    */
  final case class Options(reuseAddress: Boolean = false, broadcast: Boolean = false,
      receiveBufferBytes: Int = 4 * 1024 * 1024,
      maxDatagramsPerSecond: Int = 0,
      trusted: java.net.InetAddress => Boolean = _ => false)

  /** The current second's count of datagrams handed on and dropped; a pure step per datagram. */
  private[link] final case class RateWindow(startNanos: Long, passed: Int, dropped: Long,
      lastDropped: Option[InetSocketAddress]) {

    /** The window after a datagram from `from` at `nowNanos` under `cap`: whether it passes, and what the closed window
      * dropped.
      */
    def offer(nowNanos: Long, cap: Int, from: InetSocketAddress): (RateWindow, Boolean, Option[Dropped]) =
      if (cap <= 0) (this, true, None)
      else if (nowNanos - startNanos >= RateWindow.SecondNanos) {
        val closed = lastDropped.filter(_ => dropped > 0).map(Dropped(dropped, _))
        (RateWindow(nowNanos, 1, 0L, None), true, closed)
      } else if (passed < cap) (copy(passed = passed + 1), true, None)
      else (copy(dropped = dropped + 1, lastDropped = Some(from)), false, None)
  }

  private[link] object RateWindow {
    val SecondNanos: Long = 1000000000L

    /** A fresh window beginning at `nowNanos`. */
    def start(nowNanos: Long): RateWindow = RateWindow(nowNanos, 0, 0L, None)
  }

  /** A link bound to `address`, reporting to `owner`. */
  def apply(address: InetSocketAddress, owner: ActorRef[Event], options: Options = Options()): Behavior[Command] =
    Behaviors.setup { context =>
      Behaviors.withStash(1024) { stash =>
        // The socket dies with its adapter, a child of this actor, so stopping the link always closes the port.
        val adapter = context.actorOf(classic.Props(new SocketAdapter(context.self, address, options)), "socket")

        def binding: Behavior[Command] = Behaviors.receiveMessage {
          case SocketReady(socket, local) =>
            owner ! Bound(context.self, local)
            val now = System.nanoTime()
            stash.unstashAll(ready(socket, RateWindow.start(now), RateWindow.start(now)))
          case SocketFailed(reason) =>
            owner ! BindFailed(address, reason)
            Behaviors.stopped
          case Unbind =>
            Behaviors.stopped
          case other =>
            if (stash.isFull) context.log.warn("UDP link [{}] dropped a datagram to send while binding", address)
            else stash.stash(other)
            Behaviors.same
        }

        def ready(socket: classic.ActorRef, window: RateWindow, trustedWindow: RateWindow): Behavior[Command] =
          Behaviors.receiveMessage {
            case Send(bytes, to) =>
              socket ! Udp.Send(ByteString.fromArrayUnsafe(bytes), to)
              Behaviors.same
            case SocketReceived(data, from) if options.trusted(from.getAddress) =>
              val (next, passes, closed) = trustedWindow.offer(System.nanoTime(), options.maxDatagramsPerSecond, from)
              closed.foreach(d => owner ! d.copy(trusted = true))
              if (passes) owner ! Received(data.toArrayUnsafe(), from)
              if (next eq trustedWindow) Behaviors.same else ready(socket, window, next)
            case SocketReceived(data, from) =>
              val (next, passes, closed) = window.offer(System.nanoTime(), options.maxDatagramsPerSecond, from)
              closed.foreach(owner ! _)
              if (passes) owner ! Received(data.toArrayUnsafe(), from)
              if (next eq window) Behaviors.same else ready(socket, next, trustedWindow)
            case Unbind =>
              adapter ! Udp.Unbind
              Behaviors.same
            case SocketClosed =>
              Behaviors.stopped
            case SocketReady(_, _) | SocketFailed(_) =>
              Behaviors.unhandled
          }

        binding
      }
    }

  /** Akka IO's UDP speaks to classic actors only; this one translates between the socket and the typed link. */
  private final class SocketAdapter(link: ActorRef[Command], address: InetSocketAddress, options: Options)
      extends classic.Actor {
    import context.system

    override def preStart(): Unit = {
      val socketOptions = Vector[Inet.SocketOption](Inet.SO.ReceiveBufferSize(options.receiveBufferBytes)) ++
        (if (options.reuseAddress) Vector(Inet.SO.ReuseAddress(true)) else Vector.empty) ++
        (if (options.broadcast) Vector(Udp.SO.Broadcast(true)) else Vector.empty)
      IO(Udp) ! Udp.Bind(self, address, socketOptions)
    }

    def receive: Receive = {
      case Udp.Bound(local) =>
        link ! SocketReady(sender(), local)
        context.become(bound(sender()))
      case Udp.CommandFailed(_: Udp.Bind) =>
        link ! SocketFailed(s"cannot bind UDP $address")
        context.stop(self)
    }

    private def bound(socket: classic.ActorRef): Receive = {
      case Udp.Received(data, from) => link ! SocketReceived(data, from)
      case Udp.Unbound =>
        link ! SocketClosed
        context.stop(self)
      case Udp.CommandFailed(_: Udp.Send) => () // a full socket buffer drops the datagram, as UDP would
      case Udp.Unbind                     => socket ! Udp.Unbind
    }
  }
}
