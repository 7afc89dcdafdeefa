package naogateway.gateway.recording

import java.nio.file.{Files, Path, Paths}
import java.nio.file.attribute.FileTime
import java.time.Instant

import scala.concurrent.duration._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.api.recording.Decision
import naogateway.testkit.TempFiles.withTempDir

/** Recording retention: the rule over a listing, and the sweep of a real directory. */
class RetentionSpec extends AnyWordSpec with Matchers {

  private val MiB = 1024L * 1024
  private val now = Instant.parse("2026-07-20T12:00:00Z")
  private def file(name: String, mib: Long, hoursAgo: Long) =
    Retention.RecordingFile(Paths.get("rec", name), mib * MiB, now.minusSeconds(hoursAgo * 3600))
  private def names(files: Seq[Retention.RecordingFile]) = files.map(_.path.getFileName.toString)

  "The retention rule" should {
    "delete nothing while the directory is within both limits" in {
      val files = Vector(file("a.mcap", 10, 5), file("b.mcap", 10, 3))
      Retention.toDelete(files, Set.empty, now, RetentionSettings(100 * MiB, 1.day)) shouldBe empty
    }

    "delete the oldest files first until the total is within the size limit" in {
      val files = Vector(file("c.mcap", 30, 1), file("a.mcap", 30, 3), file("b.mcap", 30, 2), file("d.mcap", 30, 0))
      names(Retention.toDelete(files, Set.empty, now, RetentionSettings(70 * MiB, Duration.Zero))) shouldBe Vector(
        "a.mcap", "b.mcap")
    }

    "delete every file older than the age limit, then by size" in {
      val files =
        Vector(file("old1.mcap", 1, 400), file("old2.mcap", 1, 350), file("x.mcap", 50, 10), file("y.mcap", 50, 5))
      names(Retention.toDelete(files, Set.empty, now, RetentionSettings(60 * MiB, 14.days))) shouldBe
        Vector("old1.mcap", "old2.mcap", "x.mcap")
    }

    "never delete the current file, even when it is the oldest or alone over the limit" in {
      val current = file("now.mcap", 200, 500)
      val files = Vector(current, file("a.mcap", 10, 2), file("b.mcap", 10, 1))
      val doomed = Retention.toDelete(files, Set(current.path), now, RetentionSettings(100 * MiB, 1.day))
      names(doomed) shouldBe Vector("a.mcap", "b.mcap")
      doomed.map(_.path) should not contain current.path
    }

    "keep everything with both limits off" in {
      val files = Vector(file("a.mcap", 5000, 10000))
      Retention.toDelete(files, Set.empty, now, RetentionSettings(0, Duration.Zero)) shouldBe empty
    }

    "refuse limits too small to mean anything" in {
      an[IllegalArgumentException] should be thrownBy RetentionSettings(1000, 1.day)
      an[IllegalArgumentException] should be thrownBy RetentionSettings(0, 5.seconds)
    }
  }

  "The sweep" should {
    "delete old recordings in the directory, keep the current one and other files, and say so in its status" in {
      withTempDir("retention-spec") { dir =>
        def write(name: String, bytes: Int, hoursAgo: Long): Path = {
          val p = dir.resolve(name)
          Files.write(p, new Array[Byte](bytes))
          Files.setLastModifiedTime(p, FileTime.from(Instant.now().minusSeconds(hoursAgo * 3600)))
          p
        }
        val oldest = write("naogateway-1.mcap", 600 * 1024, 30)
        val older = write("naogateway-2.mcap", 600 * 1024, 20)
        val newer = write("naogateway-3.mcap", 600 * 1024, 10)
        val current = write("naogateway-4.mcap", 100, 40)
        val notes = write("notes.txt", 5 * 1024 * 1024, 50)
        val keeper = new RetentionKeeper(dir, RetentionSettings(MiB, 25.hours))
        val status = keeper.sweep(Set(current))
        Files.exists(oldest) shouldBe false // older than 25 h
        Files.exists(older) shouldBe false // the oldest left while over 1 MiB
        Files.exists(newer) shouldBe true
        Files.exists(current) shouldBe true // 40 h old, but being written
        Files.exists(notes) shouldBe true // not a recording
        status.files shouldBe 2
        status.deletedFiles shouldBe 2
        status.bytes shouldBe 600L * 1024 + 100
        keeper.status shouldBe status
        status.describe should startWith("kept 2 file(s), 600.1 KiB (limits 1.0 MiB, 25 h); 2 deleted so far")
      }
    }

    "find nothing in a directory that does not exist yet" in {
      val keeper = new RetentionKeeper(Paths.get("target", "no-such-recordings"), RetentionSettings.Default)
      keeper.sweep(Set.empty).files shouldBe 0
    }
  }

  "The recorder" should {
    "apply retention to its directory when it begins a file" in {
      withTempDir("retention-recorder") { dir =>
        val stale = dir.resolve("naogateway-20200101-000000-1.mcap")
        Files.write(stale, new Array[Byte](1024))
        Files.setLastModifiedTime(stale, FileTime.from(Instant.now().minusSeconds(30L * 86400)))
        val settings = RecordingSettings(enabled = true, dir, 64 * 1024, 1.minute, 1024, RetentionSettings(0, 14.days))
        val tap = new naogateway.gateway.tap.Tap
        val recorder = new Recorder(settings, "retention-spec-recorder", RobotTimeBase.Unknown, tap)
        try {
          tap.decision(Decision.Gate(open = true,
              naogateway.api.GameReading.Known(naogateway.wire.gamecontroller.GameState.Initial)))
          val deadline = 10.seconds.fromNow
          while (!recorder.stats.retention.exists(_.deletedFiles > 0) && deadline.hasTimeLeft()) Thread.sleep(20)
          Files.exists(stale) shouldBe false
          recorder.stats.retention.map(_.deletedFiles) shouldBe Some(1L)
        } finally recorder.close()
      }
    }
  }
}
