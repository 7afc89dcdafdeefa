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
    // The decode and its floor in alternating slices: on a shared machine the load moves within seconds, and two
    // figures taken one after the other measured 0.87 and 0.57 of each other in two runs.
    val (decode, baseline) = decodeAndFloor()
    println(f"[codec] status decode ${decode / 1e6}%.2f M/s, its floor ${baseline / 1e6}%.2f M/s " +
      f"(ratio ${decode / baseline}%.3f; $DecodeRounds rounds of ${SliceSeconds * 1000}%.0f ms each, alternating)")
    // What load does not move: the bytes each decode allocates (the garbage a loaded machine collects more slowly).
    val decodeBytes = allocatedPerOp(() => MessageContents.decodeFrame(frame).fold(_ => -1, _._2.robotId))
    val baselineBytes = allocatedPerOp(() => BaselineDecoder.decode(frame)._1)
    println(f"[codec] bytes allocated per status decode $decodeBytes%.0f, per floor decode $baselineBytes%.0f")
    val encode = BenchSuite.opsPerSecond(3.0) { () =>
      MessageContents.encodeFrame(contents).fold(_ => -1, _.length)
    }
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
    // The same decode once the reader has read keep-alives with telemetry too, as a gateway's does when its robots
    // send it: the optimising compiler's code then covers those branches (see docs/benchmarks.md, "Codec").
    val (mixed, mixedBaseline) = decodeAndFloor()
    println(f"[codec] status decode after telemetry ${mixed / 1e6}%.2f M/s, its floor ${mixedBaseline / 1e6}%.2f M/s " +
      f"(ratio ${mixed / mixedBaseline}%.3f)")
    ListMap(
      "codec_status_decode_ops_s" -> decode,
      "codec_status_decode_after_telemetry_over_floor" -> mixed / mixedBaseline,
      "codec_status_encode_ops_s" -> encode,
      "codec_status_decode_baseline_ops_s" -> baseline,
      "codec_keepalive_servos_decode_ops_s" -> decodeServos,
      "servo_telemetry_bytes_s_per_robot" -> perSecond,
      "servo_telemetry_team_budget_share_per_robot" -> perSecond / teamBudget
    )
  }

  /** The status decode of [[frame]] and its floor, operations per second, in alternating slices. */
  private def decodeAndFloor(): (Double, Double) =
    alternating(DecodeRounds, SliceSeconds)(
      () =>
        MessageContents.decodeFrame(frame) match {
          case Right((_, c)) => c.robotId
          case Left(_)       => -1
        },
      () => BaselineDecoder.decode(frame)._1
    )

  /** Rounds of the decode and its floor, each round one slice of each. */
  private val DecodeRounds = 15

  /** One slice of one op, in seconds. */
  private val SliceSeconds = 0.2

  /** Operations per second of `a` and of `b`, measured in `rounds` alternating slices of `sliceSeconds` each (after a
    * warm-up of both), so that both figures are taken under the same load and their ratio can be judged.
    */
  private[bench] def alternating(rounds: Int, sliceSeconds: Double)(a: () => Int, b: () => Int): (Double, Double) = {
    val slice = (sliceSeconds * 1e9).toLong
    def run(op: () => Int, limit: Long): (Long, Long) = BenchSuite.batches(op, limit)
    run(a, 1000000000L)
    run(b, 1000000000L)
    var opsA, nanosA, opsB, nanosB = 0L
    for (round <- 0 until rounds) {
      // Which goes first alternates too: neither always follows the other's garbage.
      val (first, second) = if (round % 2 == 0) (a, b) else (b, a)
      val (n1, t1) = run(first, slice)
      val (n2, t2) = run(second, slice)
      if (round % 2 == 0) { opsA += n1; nanosA += t1; opsB += n2; nanosB += t2 }
      else { opsA += n2; nanosA += t2; opsB += n1; nanosB += t1 }
    }
    (opsA * 1e9 / nanosA, opsB * 1e9 / nanosB)
  }

  /** Bytes the calling thread allocates per call of `op`, over 100000 calls (NaN without HotSpot's ThreadMXBean). */
  private def allocatedPerOp(op: () => Int): Double =
    java.lang.management.ManagementFactory.getThreadMXBean match {
      case hs: com.sun.management.ThreadMXBean =>
        val calls = 100000
        val id = Thread.currentThread().getId
        var sink = 0
        val before = hs.getThreadAllocatedBytes(id)
        var i = 0
        while (i < calls) { sink += op(); i += 1 }
        val after = hs.getThreadAllocatedBytes(id)
        if (sink == 42) println("")
        (after - before).toDouble / calls
      case _ => Double.NaN
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
