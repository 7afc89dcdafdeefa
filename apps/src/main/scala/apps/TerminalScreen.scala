package apps

import java.io.{ByteArrayInputStream, OutputStream}
import java.nio.charset.StandardCharsets

import scala.jdk.CollectionConverters._
import scala.sys.process._
import scala.util.Try

import org.jline.terminal.impl.DumbTerminal
import org.jline.terminal.{Size, Terminal, TerminalBuilder}
import org.jline.utils.{AttributedString, Display, InfoCmp}

/** The status screen on a terminal, redrawn with JLine's `Display`, which rewrites only what changed (no flicker).
  * Lines are fitted to the terminal's size, which is followed when the terminal is resized.
  */
final class TerminalScreen private (
    terminal: Terminal, size: () => Size, stop: () => Unit) extends StatusPrinter.ScreenOutput {
  private val display = new Display(terminal, true)
  private var drawn: Option[Size] = None

  def draw(lines: Vector[String]): Unit = synchronized {
    val now = size()
    val columns = if (now.getColumns > 0) now.getColumns else TerminalScreen.DefaultSize.getColumns
    val rows = if (now.getRows > 0) now.getRows else TerminalScreen.DefaultSize.getRows
    if (!drawn.contains(now)) {
      // First draw or a resized terminal: clear it and draw everything anew.
      display.clear()
      display.resize(rows, columns)
      drawn = Some(now)
    }
    // One row stays free for the cursor, so the screen never scrolls.
    val fitted = StatusView.fit(lines, columns, rows - 1)
    val cursor = new Size(columns, rows).cursorPos(fitted.size, 0)
    display.update(fitted.map(new AttributedString(_)).asJava, cursor, true)
  }

  def close(): Unit = synchronized {
    stop()
    terminal.flush()
  }
}

/** Opening the status screen on the terminal the launcher writes to. */
object TerminalScreen {

  /** The size assumed when a terminal does not tell its own. */
  val DefaultSize: Size = new Size(120, 40)

  /** A screen on the launcher's terminal. Started on a terminal, JLine's system terminal, whose size follows resizes
    * (WINCH). Forked by sbt, stdout is a pipe that sbt copies to its terminal: a terminal of type `TERM` over stdout,
    * whose size is read from the controlling terminal every two seconds.
    */
  def open(): TerminalScreen =
    if (System.console() != null) {
      val terminal = TerminalBuilder.builder().system(true).build()
      // Read once and again on each resize (WINCH), not at every redraw: some JLine providers ask `stty` for it.
      @volatile var size = terminal.getSize
      terminal.handle(Terminal.Signal.WINCH, _ => size = terminal.getSize)
      // JLine's system terminal sets Ctrl-C (INT) to the operating system's default, which ends the JVM at once: no
      // shutdown hooks, so the robots are not stopped through the middleware, the cluster node does not leave and the
      // recording's file is left without its summary. Ended this way, the JVM runs its hooks (CoordinatedShutdown).
      terminal.handle(Terminal.Signal.INT,
        _ => {
          val exit = new Thread(() => sys.exit(130), "ctrl-c")
          exit.start()
        })
      new TerminalScreen(terminal, () => size, () => ())
    } else over(System.out, sys.env.get("TERM"), fixedSize = None)

  /** A screen over `out` for a terminal of type `term` (xterm-256color when unknown), of `fixedSize`, or else of the
    * controlling terminal's size (`readSize`), read once and again on each resize: the terminal signals WINCH to its
    * foreground process group, which a JVM forked by sbt belongs to, so nothing is read while the size stands still.
    */
  def over(
      out: OutputStream,
      term: Option[String],
      fixedSize: Option[Size],
      readSize: () => Option[Size] = () => controllingTerminalSize()): TerminalScreen = {
    val terminalType = term.map(_.trim).filter(t => t.nonEmpty && t != "dumb").getOrElse("xterm-256color")
    // A terminal of that type writing straight to `out`: no pty of its own, no threads, nothing read from stdin.
    def build(tpe: String): Terminal =
      new DumbTerminal("naogateway", tpe, new ByteArrayInputStream(Array.emptyByteArray), out, StandardCharsets.UTF_8)
    /* A TERM neither JLine nor infocmp describes falls back to xterm's, which every terminal emulator in use
     * understands. */
    val known = Try(InfoCmp.getInfoCmp(terminalType)).toOption.exists(_.nonEmpty)
    val terminal = build(if (known) terminalType else "xterm-256color")
    val controlling = if (fixedSize.isEmpty) readSize() else None
    @volatile var size = fixedSize.orElse(controlling).getOrElse(DefaultSize)
    // Followed only where it could be read at all: without a controlling terminal the size stays as it is.
    val stop: () => Unit =
      if (controlling.isDefined) Resized.follow(() => readSize().foreach(size = _)) else () => ()
    new TerminalScreen(terminal, () => size, stop)
  }

  /** Who is told when this JVM receives WINCH: one handler for the process, installed on first use, and the screens
    * that follow it (a screen closed stops following).
    */
  private[apps] object Resized {
    private val followers = new java.util.concurrent.CopyOnWriteArrayList[() => Unit]()
    private lazy val installed: Boolean = Try {
      sun.misc.Signal.handle(new sun.misc.Signal("WINCH"), _ => followers.forEach(f => Try(f())))
    }.isSuccess

    /** Calls `reread` on every WINCH until the returned stop is called. */
    def follow(reread: () => Unit): () => Unit = {
      followers.add(reread)
      if (!installed) followers.remove(reread)
      () => { followers.remove(reread); () }
    }
  }

  /** The size of the controlling terminal (`stty size` on /dev/tty), if there is one. */
  private def controllingTerminalSize(): Option[Size] =
    Try(Seq("sh", "-c", "stty size < /dev/tty").!!(ProcessLogger(_ => ()))).toOption
      .flatMap(out => Try(out.trim.split("\\s+").map(_.toInt)).toOption)
      .collect { case Array(rows, cols) if rows > 0 && cols > 0 => new Size(cols, rows) }
}
