package naogateway.api.recording

/** What the last sweep of the recording directory found and did, for the status view and `robotctl doctor`. */
final case class RetentionStatus(files: Int, bytes: Long, deletedFiles: Long, deletedBytes: Long, limits: String,
    failed: Option[String]) {

  /** One line: "kept 12 files, 96.0 MiB (limits 20 GiB, 14 days); 3 deleted so far". */
  def describe: String =
    s"kept $files file(s), ${RetentionStatus.bytesText(bytes)} (limits $limits); $deletedFiles deleted so far" +
      failed.fold("")(f => s"; $f")
}

/** Sizes in words, for the retention status and the recorder's logs. */
object RetentionStatus {

  /** 1536 → "1.5 KiB". */
  def bytesText(bytes: Long): String = {
    val units = Vector("B", "KiB", "MiB", "GiB", "TiB")
    var value = bytes.toDouble
    var unit = 0
    while (value >= 1024 && unit < units.size - 1) { value /= 1024; unit += 1 }
    if (unit == 0) s"$bytes B" else f"$value%.1f ${units(unit)}"
  }
}

/** What the recorder did so far: files begun, MCAP messages written, entries dropped because its queue was full, and
  * entries lost because no file could be written.
  */
final case class RecordingStats(enabled: Boolean, files: Long, messages: Long, dropped: Long, failed: Long,
    currentFile: Option[String],
    retention: Option[RetentionStatus] = None)

/** The figures of a gateway that records nothing. */
object RecordingStats {

  /** Recording is off: nothing begun, written, dropped or lost. */
  val Off: RecordingStats = RecordingStats(enabled = false, 0, 0, 0, 0, None)
}
