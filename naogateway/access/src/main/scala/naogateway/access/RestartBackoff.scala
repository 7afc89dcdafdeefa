package naogateway.access

import scala.concurrent.duration._
import scala.jdk.DurationConverters._

import com.typesafe.config.Config

/** How a supervisor restarts a failed actor: the pause doubles from `minBackoff` up to `maxBackoff`, with jitter. */
final case class RestartBackoff(minBackoff: FiniteDuration, maxBackoff: FiniteDuration, randomFactor: Double) {
  require(minBackoff > Duration.Zero && maxBackoff >= minBackoff,
    "a restart back-off needs 0 < min-backoff <= max-backoff")
  require(randomFactor >= 0 && randomFactor <= 1, "a restart back-off's random-factor must be between 0 and 1")

  /** The supervisor strategy of these figures. */
  def strategy: akka.actor.typed.BackoffSupervisorStrategy =
    akka.actor.typed.SupervisorStrategy.restartWithBackoff(minBackoff, maxBackoff, randomFactor)
}

/** Reading a restart back-off block (`min-backoff`, `max-backoff`, `random-factor`). */
object RestartBackoff {

  /** The back-off of block `c`; `key` names it in the error of a bad value. */
  def fromConfig(c: Config, key: String): RestartBackoff = {
    val b = c.getConfig(key)
    try RestartBackoff(b.getDuration("min-backoff").toScala, b.getDuration("max-backoff").toScala,
        b.getDouble("random-factor"))
    catch {
      case e: IllegalArgumentException =>
        throw new IllegalArgumentException(s"$key: ${e.getMessage.stripPrefix("requirement failed: ")}")
    }
  }
}
