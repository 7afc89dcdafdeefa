package naogateway.sim

import naogateway.proto.ServoState
import naogateway.wire.Posture

/** The simulated robot's servos when no emulated bus is given (`FirmwareSettings.servoSource` None): 18 AX-12As of a
  * Bioloid-class humanoid (ids 1–18) near the centre, bent by the posture, on the battery's voltage, warm.
  */
private[sim] object ServoModel {

  /** The servo ids of a Bioloid-class humanoid. */
  val Ids: Range = 1 to 18

  /** The servos of `s` as the telemetry reads them (docs/protocol.md 6.8: raw control-table units). */
  def servos(s: FirmwareState): Vector[ServoState] = {
    val walking = s.walk.isDefined
    // Legs (ids 7-18) bend when sitting or crouching; walking swings them a little with the robot's clock.
    val bend = s.posture match {
      case Posture.Sit    => 120
      case Posture.Crouch => 60
      case _              => 0
    }
    val swing = if (walking) (40 * math.sin(s.uptimeMillis / 250.0)).round.toInt else 0
    // The servos see the battery less the drop in the wiring; tenths of a volt, as the control table holds it.
    val volts = math.max(0L, ((s.battery - 0.2) * 10).round).toInt
    Ids.toVector.map { id =>
      val side = if (id % 2 == 0) -1 else 1
      val leg = id >= 7
      val position = 512 + (if (leg) side * (bend + swing) else side * (id * 5))
      val load = side * (if (leg) 60 + bend / 2 + (if (walking) 80 else 0) else 10 + id)
      val temperature = 36 + (id * 3) % 7 + (if (walking && leg) 3 else 0)
      ServoState(id, position = Some(math.max(0, math.min(1023, position))), load = Some(load), voltage = Some(volts),
        temperature = Some(temperature))
    }
  }
}
