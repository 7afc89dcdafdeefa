package naogateway.api

/** What the gateway knows of one robot's clock: when (on the gateway's clock) the robot's clock read `robotMillis`, how
  * fast it runs, and how far off that may be.
  *
  * The gateway's clock is its JVM's `System.nanoTime`, the base of `RobotSnapshot.receivedAtNanos`. One-way observation
  * cannot tell a constant part of the link's delay from an offset: the estimate places a robot reading at the moment
  * its fastest keep-alives would have been received, so the common least delay of the link (on loopback well under 1
  * ms, on a base station's WiFi a few ms) is inside the offset and outside the bound.
  *
  * @param robotMillis
  *   the reading the estimate is anchored at (the newest keep-alive's robot time)
  * @param gatewayNanos
  *   when the robot's clock read `robotMillis`, on the gateway's clock
  * @param gatewayPerRobot
  *   gateway time per robot time (1.0: the clocks run alike)
  * @param errorBoundMillis
  *   how far `gatewayNanos` may be from the truth, in ms
  * @param boundGrowth
  *   how much the bound grows per ms of robot time away from `robotMillis`
  * @param samples
  *   keep-alives in the window the estimate rests on
  */
final case class ClockEstimate(
    robotMillis: Long,
    gatewayNanos: Long,
    gatewayPerRobot: Double,
    errorBoundMillis: Double,
    boundGrowth: Double,
    samples: Int
) {

  /** How much faster the robot's clock runs than the gateway's, in parts per million (negative: slower). */
  def driftPpm: Double = (1.0 / gatewayPerRobot - 1.0) * 1e6

  /** How far [[driftPpm]] may be from the truth, in ppm: the bound grows by the slope's own uncertainty. */
  def driftBoundPpm: Double = boundGrowth * 1e6

  /** Whether the drift is known well enough to show: right after a start its few points span seconds, and a fit over
    * them may show anything up to the ±1000 ppm it is held within, which says nothing about the robot's crystal.
    */
  def driftSettled: Boolean = driftBoundPpm <= ClockEstimate.SettledDriftPpm

  /** When the robot's clock read `robotTime` (ms), on the gateway's clock (`System.nanoTime` of the gateway's JVM). */
  def toGatewayNanos(robotTime: Long): Long =
    gatewayNanos + math.round((robotTime - robotMillis).toDouble * gatewayPerRobot * 1e6)

  /** The error bound of [[toGatewayNanos]] at `robotTime`, in ms. */
  def errorBoundAt(robotTime: Long): Double =
    errorBoundMillis + boundGrowth * math.abs((robotTime - robotMillis).toDouble)
}

/** When a drift counts as known. */
object ClockEstimate {

  /** The drift's bound at which it is shown: crystals are within about 100 ppm, so a wider bound says nothing. */
  val SettledDriftPpm: Double = 100.0
}
