package bench

import scala.collection.immutable.ListMap

import com.google.protobuf.CodedInputStream

import naogateway.proto.Status
import naogateway.wire.MessageContents

/** Frame + Message + Status codec throughput on the docs/protocol.md 9.1 keep-alive, against a hand-written
  * protobuf-java floor; and what servo telemetry (6.8) costs: its bytes in the team's WiFi budget, and the decoding of
  * a keep-alive that carries it.
  */
object CodecBench extends Benchmark {
  val name = "codec"
  override val quietSensitive = true

  private val contents =
    MessageContents(robotId = 1, status = Some(Status(teamID = Some(1), activeAgent = Some("AgentTest"))))
  private val frame: Array[Byte] = MessageContents.encodeFrame(contents).toOption.get

  def run(): ListMap[String, Double] = {
    require(MessageContents.decodeFrame(frame).map(_._2) == Right(contents), "the codec must round-trip the example")
    require(BaselineDecoder.decode(frame) == (1, 1, "AgentTest"), "the baseline must read the example")
    val decode = BenchSuite.opsPerSecond(3.0) { () =>
      MessageContents.decodeFrame(frame) match {
        case Right((_, c)) => c.robotId
        case Left(_)       => -1
      }
    }
    val encode = BenchSuite.opsPerSecond(3.0) { () =>
      MessageContents.encodeFrame(contents).fold(_ => -1, _.length)
    }
    val baseline = BenchSuite.opsPerSecond(3.0) { () => BaselineDecoder.decode(frame)._1 }
    // The simulated robot's keep-alive with and without the telemetry of its 18 servos (the built-in model).
    val firmware = naogateway.sim.FirmwareSettings(robotId = 1)
    val robot = naogateway.sim.RobotFirmware.boot(firmware, 0L)
    val keepAlive = naogateway.sim.RobotFirmware.keepAlive(robot)
    val telemetry = naogateway.sim.RobotFirmware.servoTelemetry(robot)
    require(telemetry.servos.size == 18, "the model has 18 servos")
    val plain = MessageContents.encodeFrame(keepAlive).toOption.get
    val withServos = MessageContents.encodeFrame(keepAlive.copy(servoTelemetry = Some(telemetry))).toOption.get
    require(MessageContents.decodeFrame(withServos).map(_._2.servoTelemetry) == Right(Some(telemetry)),
      "the codec must round-trip the telemetry")
    val perSecond = (withServos.length - plain.length) * 1000.0 / firmware.servoTelemetryInterval.toMillis
    val teamBudget = com.typesafe.config.ConfigFactory.load().getInt("naogateway.budget.team-bytes-per-second")
    val decodeServos = BenchSuite.opsPerSecond(3.0) { () =>
      MessageContents.decodeFrame(withServos) match {
        case Right((_, c)) => c.robotId
        case Left(_)       => -1
      }
    }
    ListMap(
      "codec_status_decode_ops_s" -> decode,
      "codec_status_encode_ops_s" -> encode,
      "codec_status_decode_baseline_ops_s" -> baseline,
      "codec_keepalive_servos_decode_ops_s" -> decodeServos,
      "servo_telemetry_bytes_s_per_robot" -> perSecond,
      "servo_telemetry_team_budget_share_per_robot" -> perSecond / teamBudget
    )
  }

  /** The floor: the same bytes read by a minimal protobuf-java loop that knows only this message. */
  object BaselineDecoder {
    def decode(bytes: Array[Byte]): (Int, Int, String) = {
      if (bytes.length < 12 || bytes(0) != 0 || bytes(1) != 42) return (-1, -1, null)
      val in = CodedInputStream.newInstance(bytes, 12, bytes.length - 12)
      var robotId = -1
      var teamId = -1
      var agent: String = null
      var done = false
      while (!done) {
        val tag = in.readTag()
        tag match {
          case 0 => done = true
          case 8 => robotId = in.readInt32()
          case 186 => // field 23, length-delimited: Status
            val limit = in.pushLimit(in.readRawVarint32())
            var inner = false
            while (!inner) {
              val t = in.readTag()
              t match {
                case 0   => inner = true
                case 16  => teamId = in.readUInt32()
                case 98  => agent = in.readStringRequireUtf8()
                case any => if (!in.skipField(any)) inner = true
              }
            }
            in.popLimit(limit)
          case other => if (!in.skipField(other)) done = true
        }
      }
      (robotId, teamId, agent)
    }
  }
}
