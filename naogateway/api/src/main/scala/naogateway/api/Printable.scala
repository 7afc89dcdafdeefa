package naogateway.api

/** Strings from the network (a robot's role, agent or error text, a peer's header) made safe to show on a terminal, in
  * a log line or on a page: every control character (C0 including newline and tab, DEL, C1 including the 8-bit CSI) is
  * replaced by its `\uXXXX` escape, so no escape sequence a robot or a stranger sends can move a terminal's cursor,
  * retitle its window or forge a log line. The one function for this in the project.
  */
object Printable {

  /** Whether `c` is a control character of C0, DEL or C1. */
  def control(c: Char): Boolean = c < 0x20 || (c >= 0x7f && c <= 0x9f)

  /** `s` with every control character replaced by its `\uXXXX` escape; `s` itself when it has none. */
  def text(s: String): String =
    if (s == null) "null"
    else if (!s.exists(control)) s
    else {
      val b = new java.lang.StringBuilder(s.length + 16)
      s.foreach(c => if (control(c)) b.append(f"\\u${c.toInt}%04x") else b.append(c))
      b.toString
    }
}
