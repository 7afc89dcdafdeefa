package naogateway.sim

import naogateway.sim.bus.BodyPostures

/** The simulated firmware's body: its posture moves the 18 AX-12A of its emulated bus (docs/simulator.md 3.2). Pure,
  * beside [[RobotFirmware]].
  */
private[sim] object FirmwareBody {

  /** The firmware with its servos' goals sent for the pose its posture asks for, when that pose differs from the last
    * one sent: a posture change moves them to the target within the change's time, a walk alternates its two steps, a
    * stop stands. Only a new pose writes, so a tool's write over the bus bridge stays until the posture changes.
    */
  def posed(s: FirmwareState): FirmwareState =
    BodyPostures.poseOf(s.posture, s.change.map(_.target), s.now).filterNot(s.bodyPose.contains) match {
      case None => s
      case Some(pose) =>
        val within = s.change.fold(BodyPostures.StepMoveNanos)(c => math.max(0L, c.doneAt - s.now))
        s.copy(bus = BodyPostures.move(s.bus.advance(s.now).withVolts(s.battery), pose, within), bodyPose = Some(pose))
    }
}
