package naogateway.transport

/** When a counted event deserves a log line: at the 1st, 10th, 100th, ... occurrence, so floods cannot flood the log.
  */
object RateLimitedLog {

  /** Whether the `n`-th occurrence (counting from 1) is logged. */
  def due(n: Long): Boolean = {
    var m = n
    while (m >= 10 && m % 10 == 0) m /= 10
    m == 1
  }

  /** Whether any of the occurrences `before + 1` to `after` is logged: for counts that grow by more than one at a time.
    */
  def dueBetween(before: Long, after: Long): Boolean =
    after > before && (before < 1 || after.toString.length > before.toString.length || due(after))
}
