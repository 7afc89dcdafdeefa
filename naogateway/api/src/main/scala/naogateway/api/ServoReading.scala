package naogateway.api

/** One servo as the robot's latest servo telemetry found it (docs/protocol.md 6.8), in units: position raw (0–1023) and
  * in degrees from centre, load raw (−1023..1023, negative clockwise), voltage in volts, temperature in °C. A `silent`
  * servo gave no valid answer to its last read: only its id is known.
  */
final case class ServoReading(
    id: Int,
    position: Option[Int] = None,
    load: Option[Int] = None,
    voltage: Option[Double] = None,
    temperature: Option[Int] = None,
    error: Int = 0,
    silent: Boolean = false
) {

  /** The position in degrees from the centre (512), AX-12A scale: 0–1023 spans 300°. */
  def degrees: Option[Double] = position.map(p => (p - ServoReading.Centre) * ServoReading.DegreesPerUnit)
}

/** Reading a `ServoState`. */
object ServoReading {

  /** The raw position of the servo's centre. */
  val Centre: Int = 512

  /** Degrees per raw position unit of an AX-12A (0–1023 spans 300°: about 0.29°). */
  val DegreesPerUnit: Double = 300.0 / 1023

  /** The reading of one `ServoState` as it travels (voltage in tenths of a volt). */
  def read(s: naogateway.proto.ServoState): ServoReading =
    if (s.silent.contains(true)) ServoReading(s.id, silent = true)
    else
      ServoReading(
        id = s.id,
        position = s.position,
        load = s.load,
        voltage = s.voltage.map(v => (v & 0xffffffffL) / 10.0),
        temperature = s.temperature,
        error = s.error.getOrElse(0)
      )
}

/** A robot's latest servo telemetry: one reading per configured servo, the bus errors the robot counted since power-up,
  * and when the keep-alive that carried it was received (the gateway's clock, as `RobotSnapshot.receivedAtNanos`). A
  * keep-alive without telemetry leaves it as it is (docs/protocol.md 6.8).
  */
final case class ServoReadings(servos: Vector[ServoReading], busErrors: Option[Long], receivedAtNanos: Long) {

  /** The telemetry as it travelled (docs/protocol.md 6.8): what the recording and the Foxglove feed publish. */
  def toProto: naogateway.proto.ServoTelemetry =
    naogateway.proto.ServoTelemetry(
      servos.map { r =>
        if (r.silent) naogateway.proto.ServoState(r.id, silent = Some(true))
        else
          naogateway.proto.ServoState(r.id, r.position, r.load, r.voltage.map(v => (v * 10).round.toInt),
            r.temperature, Option.when(r.error != 0)(r.error))
      },
      busErrors.map(_.toInt)
    )
}

/** Reading a `ServoTelemetry`. */
object ServoReadings {

  /** The most servos one telemetry carries (docs/protocol.md 6.8); more are dropped. */
  val MaxServos: Int = 32

  /** The readings of `telemetry`, received at `receivedAtNanos`. */
  def read(telemetry: naogateway.proto.ServoTelemetry, receivedAtNanos: Long): ServoReadings =
    ServoReadings(telemetry.servos.iterator.take(MaxServos).map(ServoReading.read).toVector,
      telemetry.busErrors.map(_ & 0xffffffffL), receivedAtNanos)
}
