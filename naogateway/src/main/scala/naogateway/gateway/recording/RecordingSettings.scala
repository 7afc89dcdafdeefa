package naogateway.gateway.recording

import java.nio.file.{Path, Paths}

import scala.concurrent.duration._
import scala.jdk.DurationConverters._

import com.typesafe.config.Config

/** `naogateway.recording`: whether the gateway records, where, when a file is closed and the next begun, how many
  * entries may wait for the writer before more are dropped, and how much the directory keeps.
  */
final case class RecordingSettings(
    enabled: Boolean,
    directory: Path,
    rotateBytes: Long,
    rotateInterval: FiniteDuration,
    queueCapacity: Int,
    retention: RetentionSettings = RetentionSettings.Default,
    gameFiles: Boolean = false,
    gameQuiet: FiniteDuration = 5.seconds
) {
  require(rotateBytes >= 64 * 1024, "recording.rotate-bytes must be at least 64 KiB")
  require(rotateInterval >= 1.second, "recording.rotate-interval must be at least 1 s")
  require(queueCapacity >= 16 && queueCapacity <= 1000000, "recording.queue-capacity must be 16 to 1000000")
  require(gameQuiet >= 1.second, "recording.game-quiet must be at least 1 s")
}

/** Reading the settings. */
object RecordingSettings {

  /** Recording off (the default of every gateway built without a `recording` block). */
  val Off: RecordingSettings =
    RecordingSettings(enabled = false, Paths.get("recordings"), 64L * 1024 * 1024, 10.minutes, 65536)

  /** The settings of a `naogateway.recording` block. */
  def fromConfig(c: Config): RecordingSettings =
    RecordingSettings(
      enabled = c.getBoolean("enabled"),
      directory = Paths.get(c.getString("directory")),
      rotateBytes = c.getBytes("rotate-bytes"),
      rotateInterval = c.getDuration("rotate-interval").toScala,
      queueCapacity = c.getInt("queue-capacity"),
      retention = RetentionSettings.fromConfig(c.getConfig("retention")),
      gameFiles = c.getBoolean("game-files"),
      gameQuiet = c.getDuration("game-quiet").toScala
    )
}
