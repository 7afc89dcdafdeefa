package robotmiddleware

import naogateway.wire.{RpcMethod, RpcValue}

/** The arguments the middleware passes on to a robot: an operation outside them is refused before it is sent, with `out
  * of range: <name> <value>, allowed <range>` (docs/writing-apps.md, docs/zeromq.md 6), the same text at every door.
  * The walk's speeds are the gait's (`robotmiddleware.walk-limits`, the simulated robot's by default), which a robot
  * would clamp to silently (docs/protocol.md 7.2): refused here, so an absurd speed is an error, not a success. The
  * head's are protocol.md's; the arms' are half a turn either way, beyond which no joint goes.
  *
  * @param speed
  *   the largest forward and sideways speed, m/s
  * @param turn
  *   the largest turning speed, rad/s
  */
final case class ArgumentLimits(speed: Double, turn: Double) {
  require(speed > 0 && turn > 0, "walk-limits.speed and walk-limits.turn must be positive")

  import ArgumentLimits._

  /** The refusal text of `operation` when an argument is out of range; a raw call of a known motion is read the same
    * way (one whose parameters are not numbers is left to the robot, which answers `bad parameters:`).
    */
  def check(operation: Operation): Option[String] = operation match {
    case Operation.Walk(vx, vy, omega)  => walk(vx, vy, omega)
    case Operation.Head(pan, tilt)      => head(pan, tilt)
    case Operation.Arms(ls, le, rs, re) => arms(ls, le, rs, re)
    case Operation.RawCall(module, method, params) =>
      (RpcMethod.find(module, method), numbers(params)) match {
        case (Some(RpcMethod.Walk), Some(Vector(vx, vy, omega)))  => walk(vx, vy, omega)
        case (Some(RpcMethod.Head), Some(Vector(pan, tilt)))      => head(pan, tilt)
        case (Some(RpcMethod.Arms), Some(Vector(ls, le, rs, re))) => arms(ls, le, rs, re)
        case _                                                    => None
      }
    case _ => None
  }

  private def walk(vx: Double, vy: Double, omega: Double): Option[String] =
    first(Range("vx", -speed, speed)(vx), Range("vy", -speed, speed)(vy), Range("omega", -turn, turn)(omega))

  private def head(pan: Double, tilt: Double): Option[String] =
    first(Range("pan", -PanLimit, PanLimit)(pan), Range("tilt", TiltMin, TiltMax)(tilt))

  private def arms(values: Double*): Option[String] =
    first(ArmNames.zip(values).map { case (name, v) => Range(name, -JointLimit, JointLimit)(v) }: _*)

  private def first(checks: Option[String]*): Option[String] = checks.flatten.headOption
}

/** The fixed limits, and reading the configured ones. */
object ArgumentLimits {

  /** The head's pan limit either way, rad (docs/protocol.md 7.2). */
  val PanLimit: Double = 2.0

  /** The head's tilt limits, rad (docs/protocol.md 7.2; positive looks down). */
  val TiltMin: Double = -0.6
  val TiltMax: Double = 0.5

  /** The arm joints' limit either way, rad: half a turn. */
  val JointLimit: Double = math.Pi

  /** The prefix of every refusal text, as the robot's own `out of range:` error (docs/protocol.md 7.4). */
  val Prefix: String = "out of range: "

  private val ArmNames = Vector("leftShoulder", "leftElbow", "rightShoulder", "rightElbow")

  /** The simulated robot's gait (naogateway.sim.FirmwareSettings' maxSpeed and maxTurn). */
  val Default: ArgumentLimits = ArgumentLimits(0.3, 1.0)

  /** The refusal text of `value` for `name` outside `min..max`, or None inside (a non-finite value is outside). */
  private final case class Range(name: String, min: Double, max: Double) {
    def apply(value: Double): Option[String] =
      if (!value.isNaN && value >= min && value <= max) None
      else Some(s"$Prefix$name ${show(value)}, allowed ${show(min)}..${show(max)}")
  }

  /** A number as people read it: at most three decimals, a whole one with `.0`. */
  def show(value: Double): String =
    if (value.isNaN || value.isInfinite) value.toString
    else {
      val text = BigDecimal(value).setScale(3, BigDecimal.RoundingMode.HALF_UP).bigDecimal.stripTrailingZeros
        .toPlainString
      if (text.contains('.')) text else s"$text.0"
    }

  private def numbers(params: Vector[RpcValue]): Option[Vector[Double]] = {
    val values = params.collect {
      case RpcValue.Number(f) => f.toDouble
      case RpcValue.UInt(i)   => i.toDouble
    }
    if (values.length == params.length) Some(values) else None
  }
}
