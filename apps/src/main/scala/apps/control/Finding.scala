package apps.control

/** One of `robotctl doctor`'s checks: `problem` false when all is well (then `text` says what was found), else the fix.
  * The launcher's doctor makes them; the control port sends their lines.
  */
final case class Finding(check: String, text: String, problem: Boolean, fix: String = "") {

  /** The line robotctl prints: "ok   check: text" or "FAIL check: text; fix: ...". */
  def line: String = if (problem) s"FAIL $check: $text; fix: $fix" else s"ok   $check: $text"
}
