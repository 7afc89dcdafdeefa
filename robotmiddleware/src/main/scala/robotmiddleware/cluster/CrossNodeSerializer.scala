package robotmiddleware.cluster

import naogateway.wire.ActuatorGroup

import java.io.NotSerializableException

import akka.actor.ExtendedActorSystem
import akka.actor.typed.scaladsl.adapter._
import akka.actor.typed.{ActorRef, ActorRefResolver}
import akka.serialization.SerializerWithStringManifest
import com.google.protobuf.ByteString
import scalapb.GeneratedMessage

import naogateway.api.{
  CallResult,
  GameStateUpdated,
  LinkQualityChanged,
  LinkStats,
  RobotFailure,
  RobotForgotten,
  RobotOffline,
  RobotOnline,
  RobotRestarted,
  RobotSnapshot,
  RobotStatusUpdated,
  VisionFrame
}
import naogateway.wire.gamecontroller.{GameControlData, GameControllerCodec}
import naogateway.wire.{HaViMoGrid, RpcValue}
import robotmiddleware._
import robotmiddleware.cluster.{proto => pb}

/** Akka serializer of every message that crosses the nodes of a robot cluster: protobuf through the ScalaPB classes of
  * `robotmiddleware/cluster/proto/cluster.proto`, one manifest per message class. The bindings are in this module's
  * `reference.conf`.
  *
  * GameController packets travel as their `RGme` bytes, the codec the gateway already has. A `RobotFailure` arrives as
  * the same case class without the sender's stack trace.
  */
final class CrossNodeSerializer(system: ExtendedActorSystem) extends SerializerWithStringManifest {
  import CrossNodeSerializer.{Manifest => M}
  import CrossNodeProtos._

  // Akka reserves 0-40 for itself; every node must use the same number, so it never changes.
  override def identifier: Int = 5301

  // Lazy: Akka builds serializers while the actor system is still starting.
  private lazy val resolver = ActorRefResolver(system.toTyped)

  private def refText(ref: ActorRef[_]): String = resolver.toSerializationFormat(ref)
  private def ref[T](text: String): ActorRef[T] = resolver.resolveActorRef[T](text)

  override def manifest(o: AnyRef): String = o match {
    case _: RobotMiddleware.RegisterApp       => M.RegisterApp
    case _: RobotMiddleware.Execute           => M.Execute
    case _: RobotMiddleware.Send              => M.Send
    case _: RobotMiddleware.Acquire           => M.Acquire
    case _: RobotMiddleware.Release           => M.Release
    case _: RobotMiddleware.ListRobots        => M.ListRobots
    case _: RobotMiddleware.WatchStatus       => M.WatchStatus
    case _: RobotMiddleware.WatchVision       => M.WatchVision
    case _: RobotMiddleware.WatchLinkStats    => M.WatchLinkStats
    case _: RobotMiddleware.WatchGame         => M.WatchGame
    case _: RobotMiddleware.WatchEvents       => M.WatchEvents
    case _: RobotMiddleware.AppRegistered     => M.AppRegistered
    case _: CallResult                        => M.CallResult
    case _: RobotMiddleware.LeaseResult       => M.LeaseResult
    case _: RobotMiddleware.SendResult        => M.SendResult
    case _: RobotMiddleware.RobotList         => M.RobotSnapshots
    case _: Operation                         => M.Operation
    case _: RobotFailure                      => M.RobotFailure
    case _: SessionMessage.SubscribeAppEvents => M.SubscribeAppEvents
    case SessionMessage.Close                 => M.Close
    case _: AppEvent.LeasePreempted           => M.LeasePreempted
    case _: AppEvent.SafetyStop               => M.SafetyStop
    case _: AppEvent.SafetyCleared            => M.SafetyCleared
    case _: RobotSnapshot                     => M.RobotSnapshot
    case _: LinkStats                         => M.LinkStats
    case _: VisionFrame.Regions               => M.VisionRegions
    case _: VisionFrame.Grid                  => M.VisionGrid
    case _: RobotOnline                       => M.RobotOnline
    case _: RobotOffline                      => M.RobotOffline
    case _: LinkQualityChanged                => M.LinkQualityChanged
    case _: RobotStatusUpdated                => M.RobotStatusUpdated
    case _: RobotRestarted                    => M.RobotRestarted
    case _: RobotForgotten                    => M.RobotForgotten
    case _: GameStateUpdated                  => M.GameStateUpdated
    case _: GameControlData                   => M.GameControlData
    case _: RpcValue                          => M.RpcValue
    case other                                => throw unknown(other)
  }

  override def toBinary(o: AnyRef): Array[Byte] = o match {
    case RobotMiddleware.RegisterApp(name, priority, events, replyTo) =>
      bytes(pb.RegisterApp(name, priority, refText(events), refText(replyTo)))
    case RobotMiddleware.Execute(app, robotId, operation, replyTo) =>
      bytes(pb.Execute(refText(app), robotId, toProto(operation), refText(replyTo)))
    case RobotMiddleware.Send(app, robotId, operation, replyTo) =>
      bytes(pb.Send(refText(app), robotId, toProto(operation), refText(replyTo)))
    case RobotMiddleware.Acquire(app, robotId, groups, replyTo) =>
      bytes(pb.Acquire(refText(app), robotId, groupNames(groups), refText(replyTo)))
    case RobotMiddleware.Release(app, robotId, group)     => bytes(pb.Release(refText(app), robotId, group.name))
    case RobotMiddleware.ListRobots(replyTo)              => bytes(pb.ListRobots(refText(replyTo)))
    case RobotMiddleware.WatchStatus(robotId, subscriber) => bytes(pb.WatchStatus(robotId, refText(subscriber)))
    case RobotMiddleware.WatchVision(robotId, subscriber, grid) =>
      bytes(pb.WatchVision(robotId, refText(subscriber), grid))
    case RobotMiddleware.WatchLinkStats(robotId, subscriber) => bytes(pb.WatchLinkStats(robotId, refText(subscriber)))
    case RobotMiddleware.WatchGame(subscriber)               => bytes(pb.Watch(refText(subscriber)))
    case RobotMiddleware.WatchEvents(subscriber)             => bytes(pb.Watch(refText(subscriber)))
    case RobotMiddleware.AppRegistered(name)                 => bytes(pb.AppRegistered(name))
    case CallResult(robotId, operation, result) =>
      val r = result.fold(
        f => pb.CallResult.Result.Failure(toProto(f)),
        v => pb.CallResult.Result.Returned(pb.Returned(v.map(_.toProto)))
      )
      bytes(pb.CallResult(robotId, operation, r))
    case RobotMiddleware.LeaseResult(robotId, groups, result) =>
      bytes(pb.LeaseResult(robotId, groupNames(groups), result.left.toOption.map(f => toProto(f))))
    case RobotMiddleware.SendResult(robotId, operation, result) =>
      bytes(pb.SendResult(robotId, operation, result.left.toOption.map(f => toProto(f))))
    case RobotMiddleware.RobotList(robots)              => bytes(pb.RobotSnapshots(robots.map(s => toProto(s))))
    case o: Operation                                   => bytes(toProto(o))
    case f: RobotFailure                                => bytes(toProto(f))
    case SessionMessage.SubscribeAppEvents(subscriber)  => bytes(pb.SubscribeAppEvents(refText(subscriber)))
    case SessionMessage.Close                           => Array.emptyByteArray
    case AppEvent.LeasePreempted(robotId, group, byApp) => bytes(pb.LeasePreempted(robotId, group.name, byApp))
    case AppEvent.SafetyStop(robotId, reason)           => bytes(pb.SafetyStop(robotId, reason))
    case AppEvent.SafetyCleared(robotId)                => bytes(pb.SafetyCleared(robotId))
    case s: RobotSnapshot                               => bytes(toProto(s))
    case s: LinkStats =>
      bytes(pb.LinkStats(s.robotId, s.datagramsIn, s.datagramsOut, s.bytesIn, s.bytesOut, s.rttMillis, s.lossEstimate,
          s.retransmissions, s.rejected))
    case VisionFrame.Regions(robotId, frame, timestampMs, regions) =>
      bytes(pb.VisionRegions(robotId, frame, timestampMs, regions.map(r => toProto(r))))
    case VisionFrame.Grid(robotId, frame, timestampMs, grid) =>
      bytes(pb.VisionGrid(robotId, frame, timestampMs, ByteString.copyFrom(grid.cells.toArray)))
    case RobotOnline(robotId, address)             => bytes(pb.RobotOnline(robotId, toProto(address)))
    case RobotOffline(robotId, reason)             => bytes(pb.RobotOffline(robotId, reason))
    case LinkQualityChanged(robotId, quality)      => bytes(pb.LinkQualityChanged(robotId, toProto(quality)))
    case RobotStatusUpdated(snapshot)              => bytes(toProto(snapshot))
    case RobotRestarted(robotId, bootId, resynced) => bytes(pb.RobotRestarted(robotId, bootId, resynced))
    case RobotForgotten(robotId, reason)           => bytes(pb.RobotForgotten(robotId, reason))
    case GameStateUpdated(data)                    => gamePacket(data)
    case data: GameControlData                     => gamePacket(data)
    case v: RpcValue                               => bytes(v.toProto)
    case other                                     => throw unknown(other)
  }

  override def fromBinary(bytes: Array[Byte], manifest: String): AnyRef = manifest match {
    case M.RegisterApp =>
      val m = pb.RegisterApp.parseFrom(bytes)
      RobotMiddleware.RegisterApp(m.name, m.priority, ref(m.events), ref(m.replyTo))
    case M.Execute =>
      val m = pb.Execute.parseFrom(bytes)
      RobotMiddleware.Execute(ref(m.app), m.robotId, fromProto(m.operation), ref(m.replyTo))
    case M.Send =>
      val m = pb.Send.parseFrom(bytes)
      RobotMiddleware.Send(ref(m.app), m.robotId, fromProto(m.operation), ref(m.replyTo))
    case M.Acquire =>
      val m = pb.Acquire.parseFrom(bytes)
      RobotMiddleware.Acquire(ref(m.app), m.robotId, m.groups.map(group(M.Acquire, _)).toSet, ref(m.replyTo))
    case M.Release =>
      val m = pb.Release.parseFrom(bytes)
      RobotMiddleware.Release(ref(m.app), m.robotId, group(M.Release, m.group))
    case M.ListRobots => RobotMiddleware.ListRobots(ref(pb.ListRobots.parseFrom(bytes).replyTo))
    case M.WatchStatus =>
      val m = pb.WatchStatus.parseFrom(bytes)
      RobotMiddleware.WatchStatus(m.robotId, ref(m.subscriber))
    case M.WatchVision =>
      val m = pb.WatchVision.parseFrom(bytes)
      RobotMiddleware.WatchVision(m.robotId, ref(m.subscriber), m.grid)
    case M.WatchLinkStats =>
      val m = pb.WatchLinkStats.parseFrom(bytes)
      RobotMiddleware.WatchLinkStats(m.robotId, ref(m.subscriber))
    case M.WatchGame     => RobotMiddleware.WatchGame(ref(pb.Watch.parseFrom(bytes).subscriber))
    case M.WatchEvents   => RobotMiddleware.WatchEvents(ref(pb.Watch.parseFrom(bytes).subscriber))
    case M.AppRegistered => RobotMiddleware.AppRegistered(pb.AppRegistered.parseFrom(bytes).name)
    case M.CallResult =>
      val m = pb.CallResult.parseFrom(bytes)
      val result = m.result match {
        case pb.CallResult.Result.Failure(f)  => Left(fromProto(f))
        case pb.CallResult.Result.Returned(r) => Right(r.value.map(naogateway.wire.RpcValue.fromProto))
        case pb.CallResult.Result.Empty       => throw corrupt(manifest, "neither failure nor result")
      }
      CallResult(m.robotId, m.operation, result)
    case M.LeaseResult =>
      val m = pb.LeaseResult.parseFrom(bytes)
      RobotMiddleware.LeaseResult(m.robotId, m.groups.map(group(M.LeaseResult, _)).toSet,
        m.failure.map(f => fromProto(f)).toLeft(()))
    case M.SendResult =>
      val m = pb.SendResult.parseFrom(bytes)
      RobotMiddleware.SendResult(m.robotId, m.operation, m.failure.map(f => fromProto(f)).toLeft(()))
    case M.RobotSnapshots =>
      RobotMiddleware.RobotList(pb.RobotSnapshots.parseFrom(bytes).robots.iterator.map(s => fromProto(s)).toVector)
    case M.Operation    => fromProto(pb.Operation.parseFrom(bytes))
    case M.RobotFailure => fromProto(pb.RobotFailure.parseFrom(bytes))
    case M.SubscribeAppEvents =>
      SessionMessage.SubscribeAppEvents(ref(pb.SubscribeAppEvents.parseFrom(bytes).subscriber))
    case M.Close => SessionMessage.Close
    case M.LeasePreempted =>
      val m = pb.LeasePreempted.parseFrom(bytes)
      AppEvent.LeasePreempted(m.robotId, group(M.LeasePreempted, m.group), m.byApp)
    case M.SafetyStop =>
      val m = pb.SafetyStop.parseFrom(bytes)
      AppEvent.SafetyStop(m.robotId, m.reason)
    case M.SafetyCleared => AppEvent.SafetyCleared(pb.SafetyCleared.parseFrom(bytes).robotId)
    case M.RobotSnapshot => fromProto(pb.RobotSnapshot.parseFrom(bytes))
    case M.LinkStats =>
      val m = pb.LinkStats.parseFrom(bytes)
      naogateway.api.LinkStats(m.robotId, m.datagramsIn, m.datagramsOut, m.bytesIn, m.bytesOut, m.rttMillis,
        m.lossEstimate,
        m.retransmissions, m.rejected)
    case M.VisionRegions =>
      val m = pb.VisionRegions.parseFrom(bytes)
      VisionFrame.Regions(m.robotId, m.frame, m.timestampMs, m.regions.iterator.map(r => fromProto(r)).toVector)
    case M.VisionGrid =>
      val m = pb.VisionGrid.parseFrom(bytes)
      VisionFrame.Grid(m.robotId, m.frame, m.timestampMs, HaViMoGrid(m.cells.toByteArray.toVector))
    case M.RobotOnline =>
      val m = pb.RobotOnline.parseFrom(bytes)
      naogateway.api.RobotOnline(m.robotId, fromProto(m.address))
    case M.RobotOffline =>
      val m = pb.RobotOffline.parseFrom(bytes)
      naogateway.api.RobotOffline(m.robotId, m.reason)
    case M.LinkQualityChanged =>
      val m = pb.LinkQualityChanged.parseFrom(bytes)
      naogateway.api.LinkQualityChanged(m.robotId, fromProto(m.quality))
    case M.RobotStatusUpdated => naogateway.api.RobotStatusUpdated(fromProto(pb.RobotSnapshot.parseFrom(bytes)))
    case M.RobotRestarted =>
      val m = pb.RobotRestarted.parseFrom(bytes)
      naogateway.api.RobotRestarted(m.robotId, m.bootId, m.resynced.toVector)
    case M.RobotForgotten =>
      val m = pb.RobotForgotten.parseFrom(bytes)
      naogateway.api.RobotForgotten(m.robotId, m.reason)
    case M.GameStateUpdated => naogateway.api.GameStateUpdated(gameData(bytes))
    case M.GameControlData  => gameData(bytes)
    case M.RpcValue         => naogateway.wire.RpcValue.fromProto(naogateway.proto.MixedValue.parseFrom(bytes))
    case other =>
      throw new NotSerializableException(s"CrossNodeSerializer has no message with manifest [$other]")
  }

  private def bytes(m: GeneratedMessage): Array[Byte] = m.toByteArray

  private def unknown(o: AnyRef): IllegalArgumentException =
    new IllegalArgumentException(s"CrossNodeSerializer cannot serialize [${o.getClass.getName}]; see docs/cluster.md")

  // In the docs' order, so the same set always gives the same bytes.
  private def groupNames(groups: Set[ActuatorGroup]): Seq[String] = ActuatorGroup.all.filter(groups).map(_.name)

  private def gamePacket(data: GameControlData): Array[Byte] =
    GameControllerCodec.encodeControl(data).fold(e => throw unfitGame(e.describe), identity)

  private def unfitGame(detail: String): IllegalArgumentException =
    new IllegalArgumentException(s"CrossNodeSerializer: GameControlData does not fit its RGme layout: $detail")

  private def gameData(bytes: Array[Byte]): GameControlData =
    GameControllerCodec.decodeControl(bytes).fold(e => throw corrupt(M.GameControlData, e.describe), identity)
}

/** The manifests of `CrossNodeSerializer`: short, stable names that stay valid when classes move. */
object CrossNodeSerializer {

  /** One name per message kind; renaming one breaks rolling updates between nodes of different versions. */
  object Manifest {
    val RegisterApp = "RegisterApp"
    val Execute = "Execute"
    val Send = "Send"
    val Acquire = "Acquire"
    val Release = "Release"
    val ListRobots = "ListRobots"
    val WatchStatus = "WatchStatus"
    val WatchVision = "WatchVision"
    val WatchLinkStats = "WatchLinkStats"
    val WatchGame = "WatchGame"
    val WatchEvents = "WatchEvents"
    val AppRegistered = "AppRegistered"
    val CallResult = "CallResult"
    val LeaseResult = "LeaseResult"
    val SendResult = "SendResult"
    val RobotSnapshots = "RobotSnapshots"
    val Operation = "Operation"
    val RobotFailure = "RobotFailure"
    val SubscribeAppEvents = "SubscribeAppEvents"
    val Close = "Close"
    val LeasePreempted = "LeasePreempted"
    val SafetyStop = "SafetyStop"
    val SafetyCleared = "SafetyCleared"
    val RobotSnapshot = "RobotSnapshot"
    val LinkStats = "LinkStats"
    val VisionRegions = "VisionRegions"
    val VisionGrid = "VisionGrid"
    val RobotOnline = "RobotOnline"
    val RobotOffline = "RobotOffline"
    val LinkQualityChanged = "LinkQualityChanged"
    val RobotStatusUpdated = "RobotStatusUpdated"
    val RobotRestarted = "RobotRestarted"
    val RobotForgotten = "RobotForgotten"
    val GameStateUpdated = "GameStateUpdated"
    val GameControlData = "GameControlData"
    val RpcValue = "RpcValue"
  }
}
