package naogateway.gateway.recording

import java.io.IOException
import java.nio.file.{Files, Path}
import java.time.Instant

import scala.concurrent.duration._
import scala.jdk.CollectionConverters._
import scala.jdk.DurationConverters._
import scala.util.Using
import scala.util.control.NonFatal

import com.typesafe.config.Config
import org.slf4j.LoggerFactory

import naogateway.api.recording.RetentionStatus

/** `naogateway.recording.retention`: how much the recording directory may hold and for how long. Without a limit a base
  * station that records every game runs out of disk during a competition week.
  *
  * @param maxTotalBytes
  *   the recordings together; beyond it the oldest files are deleted (0 = no size limit)
  * @param maxAge
  *   a file older than this (by its last write) is deleted (0 = no age limit)
  */
final case class RetentionSettings(maxTotalBytes: Long, maxAge: FiniteDuration) {
  require(maxTotalBytes == 0 || maxTotalBytes >= 1024L * 1024,
    "recording.retention.max-total-bytes must be 0 (no limit) or at least 1 MiB")
  require(maxAge == Duration.Zero || maxAge >= 1.minute,
    "recording.retention.max-age must be 0 (no limit) or at least 1 minute")

  /** The limits in words, for the status view: "20 GiB, 14 days". */
  def describe: String = {
    val size = if (maxTotalBytes == 0) "no size limit" else Retention.bytesText(maxTotalBytes)
    val age = if (maxAge == Duration.Zero) "no age limit" else Retention.ageText(maxAge)
    s"$size, $age"
  }
}

/** Reading the settings. */
object RetentionSettings {

  /** A competition week on a laptop: a team's five robots with debug output record well under 100 MB an hour, so a week
    * of twelve-hour days is under 10 GB; 20 GiB and 14 days keep it with room to spare, and the travel home.
    */
  val Default: RetentionSettings = RetentionSettings(20L * 1024 * 1024 * 1024, 14.days)

  /** The settings of a `naogateway.recording.retention` block. */
  def fromConfig(c: Config): RetentionSettings =
    RetentionSettings(c.getBytes("max-total-bytes"), c.getDuration("max-age").toScala)
}

/** The retention rule as a pure function over a listing, and the sweep of a directory that applies it. */
object Retention {

  /** A recording on disk: where, how big, and when it was last written. */
  final case class RecordingFile(path: Path, bytes: Long, modified: Instant)

  /** The files of a recording directory the rule applies to: every MCAP file in it (not below it). */
  def isRecording(path: Path): Boolean = path.getFileName.toString.endsWith(".mcap")

  /** The files to delete, oldest first: every file older than `maxAge`, then the oldest of the rest until the total is
    * within `maxTotalBytes`. Files in `current` (the file being written, the current game's) are never deleted and
    * count towards the total, so a current file larger than the limit leaves the others deleted and itself kept. Age is
    * by last write; files written in the same instant go by name (the recorder's names sort by start time).
    */
  def toDelete(files: Seq[RecordingFile], current: Set[Path], now: Instant, settings: RetentionSettings)
      : Vector[RecordingFile] = {
    val oldestFirst = files.toVector.sortBy(f => (f.modified, f.path.getFileName.toString))
    val deletable = oldestFirst.filterNot(f => current.contains(f.path))
    val tooOld =
      if (settings.maxAge == Duration.Zero) Vector.empty
      else {
        val cutoff = now.minus(settings.maxAge.toJava)
        deletable.filter(_.modified.isBefore(cutoff))
      }
    val left = deletable.filterNot(tooOld.contains)
    val overSize =
      if (settings.maxTotalBytes == 0) Vector.empty
      else {
        var total = oldestFirst.filterNot(tooOld.contains).map(_.bytes).sum
        left.takeWhile { f =>
          val over = total > settings.maxTotalBytes
          if (over) total -= f.bytes
          over
        }
      }
    tooOld ++ overSize
  }

  /** The recordings in `directory` (none if it does not exist); a file that vanishes while listed is left out. */
  def list(directory: Path): Vector[RecordingFile] =
    if (!Files.isDirectory(directory)) Vector.empty
    else
      Using.resource(Files.list(directory)) { paths =>
        paths.iterator().asScala.filter(p => isRecording(p) && Files.isRegularFile(p)).flatMap { p =>
          try Some(RecordingFile(p, Files.size(p), Files.getLastModifiedTime(p).toInstant))
          catch { case _: IOException => None }
        }.toVector
      }

  /** 1536 → "1.5 KiB" ([[RetentionStatus.bytesText]]). */
  def bytesText(bytes: Long): String = RetentionStatus.bytesText(bytes)

  /** 14 days → "14 days"; shorter ages in hours or minutes. */
  def ageText(age: FiniteDuration): String =
    if (age >= 1.day && age.toHours % 24 == 0) s"${age.toDays} days"
    else if (age >= 1.hour && age.toMinutes % 60 == 0) s"${age.toHours} h"
    else s"${age.toMinutes} min"
}

/** Keeps one recording directory within its [[RetentionSettings]]: each `sweep` lists it and deletes what
  * [[Retention.toDelete]] names. Called by the recorder's writer thread whenever it begins a file (never on an actor);
  * its status is read from any thread.
  */
final class RetentionKeeper(directory: Path, settings: RetentionSettings) {
  private val log = LoggerFactory.getLogger(classOf[RetentionKeeper])
  @volatile private var last = RetentionStatus(0, 0L, 0L, 0L, settings.describe, None)

  /** What the last sweep found. */
  def status: RetentionStatus = last

  /** Deletes what the rule names, never a file of `current`; a file that cannot be deleted is named in the status. */
  def sweep(current: Set[Path], now: Instant = Instant.now()): RetentionStatus = {
    val result =
      try {
        val files = Retention.list(directory)
        val doomed = Retention.toDelete(files, current, now, settings)
        val failures = doomed.flatMap { f =>
          try { Files.deleteIfExists(f.path); None }
          catch { case e: IOException => Some(s"cannot delete ${f.path.getFileName}: ${e.getMessage}") }
        }
        val deleted = doomed.filterNot(f => Files.exists(f.path))
        if (deleted.nonEmpty)
          log.info("Recording retention ({}): deleted {} old file(s), {}", settings.describe, deleted.size,
            Retention.bytesText(deleted.map(_.bytes).sum))
        failures.foreach(f => log.warn("Recording retention: {}", f))
        val kept = files.filterNot(f => deleted.exists(_.path == f.path))
        RetentionStatus(kept.size, kept.map(_.bytes).sum, last.deletedFiles + deleted.size,
          last.deletedBytes + deleted.map(_.bytes).sum,
          settings.describe, failures.headOption)
      } catch {
        case NonFatal(e) =>
          log.warn("Recording retention: cannot list {}: {}", directory, e.getMessage)
          last.copy(failed = Some(s"cannot list $directory: ${e.getMessage}"))
      }
    last = result
    result
  }

}
