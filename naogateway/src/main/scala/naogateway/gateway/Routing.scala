package naogateway.gateway

import java.net.{InetAddress, InetSocketAddress}

import scala.collection.immutable.IntMap

import naogateway.wire._

/** Where a datagram on the robot port goes, decided without actors: the robot port's reader applies [[Routing.decide]]
  * to the table the gateway last published. The gateway alone writes the table and alone decides what the table cannot
  * (discovery, re-binding, conflicting claims); the reader hands those frames to it.
  *
  * A robot is known by its IP address, not by IP and port: the GS1500M sends from a client connection whose source port
  * changes whenever the module reconnects, while it receives on its own port (docs/protocol.md section 2), so the
  * source port says nothing about the robot.
  */
private[naogateway] object Routing {

  /** Robot `robotId`, bound to the IP address `address`, reached through `target`. */
  final case class Route[+A](robotId: Int, address: InetAddress, target: A)

  /** The datagram robots by id and by bound IP address (ZeroMQ robots are not in it); immutable, replaced whole. By id
    * in an `IntMap`: looked up once per datagram, a `Map[Int, _]` boxed the id and compared it through
    * `BoxesRunTime.equals`, a twentieth of the port loop's time under an ingest blast (profiled).
    */
  final case class Table[+A](byId: IntMap[Route[A]], byAddress: Map[InetAddress, Route[A]])

  /** Building tables. */
  object Table {

    /** No robots. */
    val empty: Table[Nothing] = Table(IntMap.empty, Map.empty)

    /** The table of `routes`. */
    def of[A](routes: Iterable[Route[A]]): Table[A] =
      Table(IntMap.from(routes.map(r => r.robotId -> r)), routes.map(r => r.address -> r).toMap)
  }

  /** What becomes of one datagram. */
  sealed trait Decision[+A] extends Product with Serializable

  /** A frame from robot `route`'s bound IP address (any source port), carrying its id: for that robot. */
  final case class ToRobot[A](route: Route[A], header: FrameHeader, contents: MessageContents, size: Int)
      extends Decision[A]

  /** A secure-stream segment from robot `route`'s bound IP address (any source port). */
  final case class SegmentToRobot[A](route: Route[A], bytes: Array[Byte]) extends Decision[A]

  /** A frame the table cannot place (an id not bound here, or bound to another address): the gateway decides. `bytes`
    * is the datagram, for the signature check of a robot that must sign.
    */
  final case class ToGateway(header: FrameHeader, contents: MessageContents, size: Int, from: InetSocketAddress,
      bytes: Array[Byte])
      extends Decision[Nothing]

  /** Rejected for `kind` (`detail`: the sender's values, for the debug log only); `route` is the robot bound to the
    * sender's address, if any (it counts the refusal too).
    */
  final case class Rejected[A](kind: Rejection, detail: String, route: Option[Route[A]]) extends Decision[A]

  /** The decision for `bytes` from `from` under `table`; total: bad bytes give [[Rejected]], never an exception. */
  def decide[A](table: Table[A], bytes: Array[Byte], from: InetSocketAddress): Decision[A] = {
    def sender = table.byAddress.get(from.getAddress)
    Datagram.classify(bytes) match {
      case Datagram.FuRemoteFrame(_) =>
        MessageContents.decodeFrame(bytes) match {
          case Right((header, contents)) =>
            table.byId.get(contents.robotId) match {
              case Some(route) if route.address == from.getAddress => ToRobot(route, header, contents, bytes.length)
              case _ => ToGateway(header, contents, bytes.length, from, bytes)
            }
          case Left(error) => Rejected(Rejection.of(error), error.describe, sender)
        }
      case Datagram.StreamSegment(_) =>
        sender match {
          case Some(route) => SegmentToRobot(route, bytes)
          case None        => Rejected(Rejection.StreamFromUnknownAddress, "", None)
        }
      case Datagram.GameControllerControl(_) | Datagram.GameControllerReturn(_) =>
        Rejected(Rejection.GameControllerOnRobotPort, "", sender)
      case Datagram.Rejected(reason, _) =>
        Rejected(Rejection.of(reason), reason.describe, sender)
    }
  }
}
