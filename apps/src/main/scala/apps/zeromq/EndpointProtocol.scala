package apps.zeromq

import naogateway.api.RobotFailure

import naogateway.wire.ActuatorGroup

import java.nio.charset.StandardCharsets

import scala.util.control.NonFatal

import com.google.protobuf.{ByteString, CodedInputStream, WireFormat}

import naogateway.proto.HaViMoRegionFrame
import naogateway.wire.gamecontroller.{GameControlData, GameControllerCodec}
import naogateway.wire.{HaViMo, MessageContents, RpcCall, RpcReply, RpcValue}
import naogateway.api.{RobotSnapshot, ServoReadings, VisionFrame}
import robotmiddleware.Operation

/** A request as the endpoint read it: the addressed robot and the call, with the client's `callId`. */
final case class EndpointRequest(robotId: Int, call: RpcCall)

/** A request the endpoint could not read, with what could be salvaged for the error reply. */
final case class Unreadable(robotId: Int, callId: Option[Long], error: String)

/** What a request asks the endpoint to do. */
sealed trait Route extends Product with Serializable

/** The requests the endpoint serves. */
object Route {

  /** `gateway.robots`: the ids of the known robots. */
  case object Robots extends Route

  /** `gateway.status`: the robot's latest keep-alive. */
  final case class Status(robotId: Int) extends Route

  /** `gateway.servos`: the robot's latest servo telemetry, hot and low-voltage servos marked. */
  final case class Servos(robotId: Int) extends Route

  /** `gateway.acquire`: take leases for the ZeroMQ clients. */
  final case class Acquire(robotId: Int, groups: Vector[ActuatorGroup]) extends Route

  /** `gateway.release`: give leases back. */
  final case class Release(robotId: Int, groups: Vector[ActuatorGroup]) extends Route

  /** A robot call: a `RobotInterface` operation, its lease taken on the clients' behalf. */
  final case class Execute(robotId: Int, operation: Operation) extends Route

  /** `gateway.send`: the operation sent through `RobotInterface.send`, lease taken the same way; the reply says it was
    * accepted, the robot's own answer is dropped.
    */
  final case class Send(robotId: Int, operation: Operation) extends Route
}

/** A successful answer: the return value, for `gateway.status` the snapshot sent along, for `gateway.servos` the servo
  * telemetry.
  */
final case class Answer(value: Option[RpcValue], snapshot: Option[RobotSnapshot] = None,
    servos: Option[ServoReadings] = None)

/** The endpoint's wire format, pure: reading requests, routing them, writing replies and publications. */
object EndpointProtocol {

  /** The module of the endpoint's own methods. */
  val GatewayModule: String = "gateway"

  /** The topic of robot `robotId`'s keep-alive snapshots. */
  def statusTopic(robotId: Int): String = s"status.$robotId"

  /** The topic of robot `robotId`'s HaViMo2 regions. */
  def visionTopic(robotId: Int): String = s"vision.$robotId"

  /** The topic of GameController packets. */
  val GameTopic: String = "game"

  /** The prefix every error text of a request the endpoint could not read starts with. */
  val Malformed: String = "malformed request: "

  /** Reads one request body: a serialized `Message` carrying an `rpcRequest`. */
  def parse(body: Array[Byte]): Either[Unreadable, EndpointRequest] =
    MessageContents.parse(body) match {
      case Left(error) =>
        val (robotId, callId) = salvage(body)
        Left(Unreadable(robotId, callId,
            s"${Malformed}not a protobuf Message with robotID and a complete rpcRequest (${error.describe})"))
      case Right(contents) =>
        contents.rpcRequest match {
          case None =>
            Left(Unreadable(contents.robotId, None, s"${Malformed}the Message carries no rpcRequest (extension 7110)"))
          case Some(request) => Right(EndpointRequest(contents.robotId, RpcCall.fromProto(request)))
        }
    }

  /** The robot id and call id of a body that did not parse, as far as they can be read, so that even the error reply
    * carries the client's call id (e.g. a `Request` without its `method`).
    */
  def salvage(body: Array[Byte]): (Int, Option[Long]) = {
    var robotId = -1
    var callId = Option.empty[Long]
    try {
      val in = CodedInputStream.newInstance(body)
      var done = false
      while (!done) {
        val tag = in.readTag()
        if (tag == 0) done = true
        else if (is(tag, 1, WireFormat.WIRETYPE_VARINT)) robotId = in.readInt32()
        else if (is(tag, MessageContents.RpcRequestField, WireFormat.WIRETYPE_LENGTH_DELIMITED)) {
          val inner = CodedInputStream.newInstance(in.readByteArray())
          var innerDone = false
          while (!innerDone) {
            val t = inner.readTag()
            if (t == 0) innerDone = true
            else if (is(t, 15, WireFormat.WIRETYPE_VARINT)) callId = Some(inner.readUInt32() & 0xffffffffL)
            else if (!inner.skipField(t)) innerDone = true
          }
        } else if (!in.skipField(tag)) done = true
      }
    } catch { case NonFatal(_) => () } // what was read before the damage is kept
    (robotId, callId)
  }

  private def is(tag: Int, field: Int, wireType: Int): Boolean =
    WireFormat.getTagFieldNumber(tag) == field && WireFormat.getTagWireType(tag) == wireType

  private def texts(call: RpcCall): Vector[String] = call.params.collect { case RpcValue.Text(t) => t }

  private def describe(params: Vector[RpcValue]): String = Operation.describe(params)

  private def groups(call: RpcCall)(route: Vector[ActuatorGroup] => Route): Either[String, Route] = {
    val names = texts(call)
    if (names.isEmpty || names.length != call.params.length)
      Left(s"$Malformed${call.name} takes one or more group names (${ActuatorGroup.all.map(_.name).mkString(", ")})")
    else
      names.distinct
        .foldLeft[Either[String, Vector[ActuatorGroup]]](Right(Vector.empty))((done, n) =>
          done.flatMap(gs => ActuatorGroup.parse(n).map(gs :+ _)))
        .left.map(Malformed + _)
        .map(route)
  }

  /** What `request` asks for, or the error text of a call whose parameters cannot be right. */
  def route(request: EndpointRequest): Either[String, Route] = {
    val EndpointRequest(robotId, call) = request
    def noParams(route: => Either[String, Route]): Either[String, Route] =
      if (call.params.isEmpty) route
      else Left(s"$Malformed${call.name} takes no parameters, got ${describe(call.params)}")
    (call.module, call.method) match {
      case (GatewayModule, "robots")  => noParams(Right(Route.Robots))
      case (GatewayModule, "status")  => noParams(Right(Route.Status(robotId)))
      case (GatewayModule, "servos")  => noParams(Right(Route.Servos(robotId)))
      case (GatewayModule, "acquire") => groups(call)(Route.Acquire(robotId, _))
      case (GatewayModule, "release") => groups(call)(Route.Release(robotId, _))
      case (GatewayModule, "send")    =>
        // The call to send is the parameters: its module, its method, then its own parameters, read as a call is.
        call.params match {
          case RpcValue.Text(module) +: RpcValue.Text(method) +: params if module != GatewayModule =>
            route(EndpointRequest(robotId, RpcCall(module, method, params, call.callId))).flatMap {
              case Route.Execute(id, operation) => Right(Route.Send(id, operation))
              case other                        => Left(s"${Malformed}gateway.send cannot send $other")
            }
          case _ =>
            Left(s"${Malformed}gateway.send takes the robot call's module and method (texts, not gateway) " +
              "and its parameters, " +
              s"got ${describe(call.params)}")
        }
      case (GatewayModule, _) => Left(RpcReply.unknownMethod(call.module, call.method))
      // A robot call: the operation the method table names (RawCall for any other), as the guard turns it back.
      case _ => Operation.fromCall(call).left.map(Malformed + _).map(Route.Execute(robotId, _))
    }
  }

  /** The error text of a failed request: a category prefix (docs/zeromq.md), then the cause. */
  def errorText(failure: Throwable): String = failure match {
    case f: RobotFailure.UnknownRobot             => s"unknown robot: ${f.getMessage}"
    case f: RobotFailure.RobotOffline             => s"offline: ${f.getMessage}"
    case f: RobotFailure.LeaseNotHeld             => s"lease: ${f.getMessage}"
    case f: RobotFailure.RuleGate                 => s"rule: ${f.getMessage}"
    case f: RobotFailure.Timeout                  => s"timeout: ${f.getMessage}"
    case RobotFailure.RobotError(_, error)        => s"robot error: $error"
    case f: RobotFailure.SafetyHold               => s"safety: ${f.getMessage}"
    case f: RobotFailure.Overloaded               => s"overloaded: ${f.getMessage}"
    case e: java.util.concurrent.TimeoutException => s"timeout: the middleware did not answer in time (${e.getMessage})"
    case e: IllegalArgumentException => Malformed + String.valueOf(e.getMessage).stripPrefix("requirement failed: ")
    case e                           => s"endpoint error: ${e.getClass.getSimpleName}: ${e.getMessage}"
  }

  /** The reply to a request: a `Message` for `robotId` with the `rpcResponse` (and the snapshot for `gateway.status`,
    * the servo telemetry for `gateway.servos`).
    */
  def reply(robotId: Int, callId: Option[Long], result: Either[String, Answer]): Array[Byte] = {
    val snapshot = result.toOption.flatMap(_.snapshot)
    MessageContents(
      robotId,
      status = snapshot.map(_.report.status),
      robotHealth = snapshot.map(_.report.health),
      servoTelemetry = result.toOption.flatMap(_.servos).map(_.toProto),
      rpcResponse = Some(RpcReply(result.map(_.value), callId).toProto)
    ).toProtobuf
  }

  /** The frames of a status publication: topic, the keep-alive as `Message` with `status` and `robotHealth`, link
    * quality.
    */
  def statusFrames(s: RobotSnapshot): Vector[Array[Byte]] =
    Vector(
      utf8(statusTopic(s.robotId)),
      s.report.contents(s.robotId).toProtobuf,
      utf8(s.quality.name)
    )

  /** The frames of a vision publication: topic and a `Message` with `havimoRegions`; grids are not published. */
  def visionFrames(frame: VisionFrame): Option[Vector[Array[Byte]]] = frame match {
    case VisionFrame.Regions(robotId, number, timestamp, regions) =>
      HaViMo.encodeRegions(regions).toOption.map { records =>
        val contents = MessageContents(robotId,
          havimoRegions = Some(HaViMoRegionFrame(number.toInt, timestamp, Some(ByteString.copyFrom(records)))))
        Vector(utf8(visionTopic(robotId)), contents.toProtobuf)
      }
    case _: VisionFrame.Grid => None
  }

  /** The frames of a game publication: topic and the GameController's control packet, byte for byte (docs/protocol.md
    * 10).
    */
  def gameFrames(data: GameControlData): Option[Vector[Array[Byte]]] =
    GameControllerCodec.encodeControl(data).toOption.map(packet => Vector(utf8(GameTopic), packet))

  /** Whether a subscription prefix takes a publication on `topic` (ZeroMQ's match: the topic starts with the prefix;
    * the empty prefix takes every topic).
    */
  def subscribed(prefixes: Set[String], topic: String): Boolean = prefixes.exists(p => topic.startsWith(p))

  /** Whether a subscription prefix asks for robot `robotId`'s vision; only prefixes naming the vision topics count. */
  def wantsVision(prefixes: Set[String], robotId: Int): Boolean =
    prefixes.exists(p => p.startsWith("vision") && visionTopic(robotId).startsWith(p))

  private def utf8(s: String): Array[Byte] = s.getBytes(StandardCharsets.UTF_8)
}
