package robotmiddleware

import naogateway.api.ServoReading

/** When a servo of the robot's telemetry is worth a warning (settings `robotmiddleware.servos`): `hot` at or above
  * `hotCelsius`, `lowVoltage` below `lowVolts`. Silent servos are neither: nothing of them is known.
  */
final case class ServoLimits(hotCelsius: Int = ServoLimits.DefaultHot, lowVolts: Double = ServoLimits.DefaultLow) {
  require(hotCelsius > 0 && hotCelsius <= 100, "servos.hot must be from 1 to 100 °C")
  require(lowVolts > 0.0 && lowVolts < 20.0, "servos.low-voltage must be from 0 to 20 V")

  /** The servo is at or above the warning temperature. */
  def hot(r: ServoReading): Boolean = r.temperature.exists(_ >= hotCelsius)

  /** The servo's supply is below the warning voltage. */
  def lowVoltage(r: ServoReading): Boolean = r.voltage.exists(_ < lowVolts)
}

/** The defaults, from the AX-12A's e-Manual. */
object ServoLimits {

  /** 5 °C below the AX-12A's default temperature limit (70 °C), where it shuts its torque off. */
  val DefaultHot: Int = 65

  /** 1 V above the bottom of the AX-12A's operating range (9–12 V). */
  val DefaultLow: Double = 10.0
}
