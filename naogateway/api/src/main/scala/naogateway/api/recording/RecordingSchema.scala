package naogateway.api.recording

import scala.collection.mutable

import com.google.protobuf.DescriptorProtos.FileDescriptorSet
import com.google.protobuf.Descriptors.FileDescriptor

import naogateway.proto.{BodyProto, DebuggingProto, HavimoProto, MessageProto, RecordingProto, RpcProto}

/** What a recording's channels are named and hold: the recorder writes them, and the web view's live Foxglove feed
  * names the same channels with the same schema, so a viewer shows the running gateway as it shows a recording.
  */
object RecordingSchema {

  /** Topics of a recording (docs/recording.md). */
  object Topics {
    val Datagrams: String = "/gateway/datagrams"
    val Decisions: String = "/gateway/decisions"
    def status(robotId: Int): String = s"/robot/$robotId/status"
    def health(robotId: Int): String = s"/robot/$robotId/health"
    def message(robotId: Int): String = s"/robot/$robotId/message"
    def servos(robotId: Int): String = s"/robot/$robotId/servos"
  }

  /** Robots per file that get decoded channels of their own; datagrams of further robot ids are kept raw only. */
  val MaxRobotChannels: Int = 64

  /** Every .proto file of the project with its imports, dependencies first: the schema data of every channel. */
  lazy val descriptorSet: Array[Byte] = {
    val ordered = mutable.LinkedHashMap.empty[String, FileDescriptor]
    def add(f: FileDescriptor): Unit = if (!ordered.contains(f.getName)) {
      f.getDependencies.forEach(d => add(d))
      ordered(f.getName) = f
    }
    Seq(
      MessageProto.javaDescriptor,
      DebuggingProto.javaDescriptor,
      HavimoProto.javaDescriptor,
      RpcProto.javaDescriptor,
      RecordingProto.javaDescriptor,
      BodyProto.javaDescriptor
    ).foreach(add)
    val set = FileDescriptorSet.newBuilder()
    ordered.values.foreach(f => set.addFile(f.toProto))
    set.build().toByteArray
  }
}
