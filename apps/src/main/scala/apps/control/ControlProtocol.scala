package apps.control

import java.nio.charset.StandardCharsets

import naogateway.wire.{Posture, RpcMethod, RpcValue}

/** The control port's wire format (docs/robotctl.md), shared by the gateway's [[ControlServer]] and the `robotctl`
  * client. Pure code with no Akka in it, so the client loads none.
  *
  * A connection carries one exchange: the client sends one request line, the server answers with any number of output
  * lines and one final line, then closes. Lines end with `\n` and are UTF-8.
  *
  *   - request: `status` | `doctor` | `call <robotId> <module> <method> [<param> ...]` | `watch <robotId> <seconds>` |
  *     `servos <robotId>` | `battery <robotId> swap`; words are separated by one space, and a param is `n:<float>`,
  *     `f:true|false` or `t:<text>`.
  *   - answer: `. <text>` for each line of output, then `ok <text>` or `error <text>`.
  *
  * Words escape `\` as `\\`, a space as `\s` and other control characters as `\uXXXX`; answer texts keep their spaces.
  */
object ControlProtocol {

  /** Where robotctl looks for the control port when told nothing else (the `apps.control.bind` default). */
  val DefaultAddress: String = "127.0.0.1:11019"

  /** The environment variable naming the control port's `host:port`, read by both the gateway and robotctl. */
  val AddressVariable: String = "NAOGATEWAY_CONTROL"

  /** The longest request line in UTF-8 bytes, without its `\n`; the server refuses longer ones. */
  val MaxRequestBytes: Int = 4096

  /** The longest answer line in UTF-8 bytes, without its `\n`; longer output is split into several lines. */
  val MaxAnswerBytes: Int = 8192

  /** What robotctl asks of the gateway. */
  sealed trait Request extends Product with Serializable

  /** The requests. */
  object Request {

    /** One line per robot. */
    case object Status extends Request

    /** One RPC call to a robot (motion and speech calls take their lease for the call). */
    final case class Call(robotId: Int, module: String, method: String, params: Vector[RpcValue]) extends Request

    /** A robot's status stream for `seconds`. */
    final case class Watch(robotId: Int, seconds: Int) extends Request

    /** A robot's servo table: its latest servo telemetry (docs/protocol.md 6.8), one line per servo. */
    final case class Servos(robotId: Int) extends Request

    /** The gateway's and the machine's checks, each problem with its fix ([[naogateway.launcher.Doctor]]). `configFile`
      * stays with robotctl: when no gateway answers, robotctl checks that file's config (ports, keys, directories)
      * itself.
      */
    final case class Doctor(configFile: Option[String] = None) extends Request

    /** Swaps a simulated robot's battery for a full one (the demo's battery swap; refused for a real robot). */
    final case class BatterySwap(robotId: Int) extends Request
  }

  /** One line of the server's answer. */
  sealed trait Answer extends Product with Serializable

  /** The answer lines. */
  object Answer {

    /** A line of output, printed as it arrives. */
    final case class Line(text: String) extends Answer

    /** The last line: the request succeeded; `text` may be empty. */
    final case class Ok(text: String) extends Answer

    /** The last line: the request failed, and why. */
    final case class Error(text: String) extends Answer
  }

  /** The command line's help. */
  val usage: String =
    """usage: robotctl [--control host:port] status                       (one line per robot)
      |       robotctl [--control host:port] call <robotId> <module> <method> [param ...]
      |                                         (numbers become floats, true/false flags, else text)
      |       robotctl [--control host:port] watch <robotId> [seconds]   (the robot's status stream; default 10 s)
      |       robotctl [--control host:port] servos <robotId>            (the robot's servo table)
      |       robotctl [--control host:port] doctor [config-file]        (what is wrong, each with its fix;
      |                                                                   exit 0 when all is well)
      |       robotctl [--control host:port] battery <robotId> swap      (a simulated robot's battery full again)
      |The gateway's control port is --control, else $NAOGATEWAY_CONTROL, else 127.0.0.1:11019.""".stripMargin

  /** Reads a command-line parameter: a number, a truth value or a text. */
  def param(text: String): RpcValue =
    text.toFloatOption.map(RpcValue.Number(_): RpcValue)
      .orElse(text.toBooleanOption.map(RpcValue.Flag(_)))
      .getOrElse(RpcValue.Text(text))

  /** Parses the command's words (after any `--control`); the usage, or a clear message, when they are wrong. */
  def parse(args: Seq[String]): Either[String, Request] = args.toList match {
    case "status" :: Nil                      => Right(Request.Status)
    case "doctor" :: file if file.sizeIs <= 1 => Right(Request.Doctor(file.headOption))
    case "servos" :: id :: Nil                => robotId(id).map(Request.Servos(_))
    case "call" :: id :: module :: method :: params =>
      robotId(id).map(Request.Call(_, module, method, params.map(param).toVector))
    case "battery" :: id :: "swap" :: Nil => robotId(id).map(Request.BatterySwap(_))
    case "watch" :: id :: rest if rest.sizeIs <= 1 =>
      for {
        robot <- robotId(id)
        seconds <- rest.headOption.fold[Either[String, Int]](Right(10))(s =>
          s.toIntOption.filter(_ > 0).toRight(s"'$s' is not a number of seconds"))
      } yield Request.Watch(robot, seconds)
    case _ => Left(usage)
  }

  private def robotId(text: String): Either[String, Int] = text.toIntOption.toRight(s"robot id '$text' is not a number")

  /** The request as one line (without `\n`). */
  def render(request: Request): String = request match {
    case Request.Status          => "status"
    case Request.Doctor(_)       => "doctor"
    case Request.Watch(id, secs) => s"watch $id $secs"
    case Request.Servos(id)      => s"servos $id"
    case Request.BatterySwap(id) => s"battery $id swap"
    case Request.Call(id, module, method, params) =>
      (Vector("call", id.toString, escapeWord(module), escapeWord(method)) ++ params.map(renderParam)).mkString(" ")
  }

  private def renderParam(value: RpcValue): String = value match {
    case RpcValue.Number(n) => s"n:${java.lang.Float.toString(n)}"
    case RpcValue.Flag(b)   => s"f:$b"
    case RpcValue.Text(t)   => s"t:${escapeWord(t)}"
    // The command line makes only the three above; anything else travels as its text.
    case other => s"t:${escapeWord(other.toString)}"
  }

  /** Reads a request line (without `\n`); a message saying what is wrong with it otherwise. */
  def readRequest(received: String): Either[String, Request] = {
    // A line typed into a terminal client may end with \r\n; a rendered line never ends with a raw \r.
    val line = received.stripSuffix("\r")
    if (utf8Length(line) > MaxRequestBytes) Left(s"request line longer than $MaxRequestBytes bytes")
    else
      line.split(" ", -1).toList match {
        case "status" :: Nil => Right(Request.Status)
        case "doctor" :: Nil => Right(Request.Doctor(None))
        case "servos" :: id :: Nil =>
          robotId(id).left.map(_ => s"robot id '${printable(id)}' is not a number").map(Request.Servos(_))
        case "battery" :: id :: "swap" :: Nil =>
          robotId(id).left.map(_ => s"robot id '${printable(id)}' is not a number").map(Request.BatterySwap(_))
        case "watch" :: id :: seconds :: Nil =>
          for {
            robot <- robotId(id)
            secs <- seconds.toIntOption.filter(_ > 0).toRight(s"'${printable(seconds)}' is not a number of seconds")
          } yield Request.Watch(robot, secs)
        case "call" :: id :: module :: method :: params =>
          for {
            robot <- robotId(id).left.map(_ => s"robot id '${printable(id)}' is not a number")
            m <- unescape(module)
            f <- unescape(method)
            ps <- params.foldLeft[Either[String, Vector[RpcValue]]](Right(Vector.empty)) { (acc, p) =>
              acc.flatMap(v => readParam(p).map(v :+ _))
            }
            _ <- postureNamed(m, f, ps)
          } yield Request.Call(robot, m, f, ps)
        case _ => Left(s"unknown request '${printable(line.take(40))}'")
      }
  }

  // A posture name is checked here, where the operator typed it, so a typo is answered at once and never moves a robot.
  private def postureNamed(module: String, method: String, params: Vector[RpcValue]): Either[String, Unit] =
    (RpcMethod.find(module, method), params) match {
      case (Some(RpcMethod.Posture), Vector(RpcValue.Text(name))) => Posture.target(name).map(_ => ())
      case _                                                      => Right(())
    }

  private def readParam(word: String): Either[String, RpcValue] =
    if (word.startsWith("n:")) {
      val text = word.drop(2)
      // Only what Float.toString writes: no trailing type letters, no hex.
      Some(text).filter(_.matches("-?(NaN|Infinity|[0-9]+\\.[0-9]+(E-?[0-9]+)?)")).flatMap(_.toFloatOption) match {
        case Some(n) => Right(RpcValue.Number(n))
        case None    => Left(s"'${printable(word.take(40))}' is not a number parameter")
      }
    } else if (word == "f:true") Right(RpcValue.Flag(true))
    else if (word == "f:false") Right(RpcValue.Flag(false))
    else if (word.startsWith("t:")) unescape(word.drop(2)).map(RpcValue.Text(_))
    else Left(s"parameter '${printable(word.take(40))}' is not n:, f: or t:")

  /** The answer line (without `\n`). */
  def render(answer: Answer): String = answer match {
    case Answer.Line(text)  => s". ${escapeText(text)}"
    case Answer.Ok(text)    => if (text.isEmpty) "ok" else s"ok ${escapeText(text)}"
    case Answer.Error(text) => s"error ${escapeText(text)}"
  }

  /** Reads an answer line (without `\n`); a message saying what is wrong with it otherwise. */
  def readAnswer(received: String): Either[String, Answer] = {
    val line = received.stripSuffix("\r")
    if (utf8Length(line) > MaxAnswerBytes) Left(s"answer line longer than $MaxAnswerBytes bytes")
    else if (line.startsWith(". ")) unescape(line.drop(2)).map(Answer.Line(_))
    else if (line == "ok") Right(Answer.Ok(""))
    else if (line.startsWith("ok ")) unescape(line.drop(3)).map(Answer.Ok(_))
    else if (line.startsWith("error ")) unescape(line.drop(6)).map(Answer.Error(_))
    else Left(s"unreadable answer line '${printable(line.take(40))}'")
  }

  /** `text` as output lines that each fit an answer line: split at its own line breaks, and long lines cut into pieces
    * (on whole characters) so that no escaped line outgrows [[MaxAnswerBytes]].
    */
  def lines(text: String): Vector[Answer.Line] = {
    // An escaped character takes at most 6 bytes (\uXXXX); a surrogate pair 4 bytes for two chars.
    val maxChars = (MaxAnswerBytes - 2) / 6
    text.split("\r?\n", -1).toVector.flatMap { line =>
      if (line.isEmpty) Vector(Answer.Line(""))
      else {
        val pieces = Vector.newBuilder[Answer.Line]
        var start = 0
        while (start < line.length) {
          var end = math.min(line.length, start + maxChars)
          if (end < line.length && Character.isHighSurrogate(line.charAt(end - 1)) && Character.isLowSurrogate(
              line.charAt(end))) end -= 1
          pieces += Answer.Line(line.substring(start, end))
          start = end
        }
        pieces.result()
      }
    }
  }

  /** Parses `host:port` (`[v6]:port` for IPv6 literals). */
  def address(text: String): Either[String, (String, Int)] = {
    val colon = text.lastIndexOf(':')
    val (host, port) = if (colon < 0) (text, "") else (text.substring(0, colon), text.substring(colon + 1))
    val bare = if (host.startsWith("[") && host.endsWith("]")) host.substring(1, host.length - 1) else host
    port.toIntOption.filter(p => p >= 0 && p <= 65535) match {
      case Some(p) if bare.nonEmpty => Right(bare -> p)
      case _                        => Left(s"'$text' is not host:port")
    }
  }

  /** A word with nothing in it that could split it or end the line. */
  def escapeWord(word: String): String = escape(word, spaces = true)

  /** A text with nothing in it that could end the line (its spaces stay). */
  def escapeText(text: String): String = escape(text, spaces = false)

  private def escape(s: String, spaces: Boolean): String = {
    val b = new java.lang.StringBuilder(s.length + 8)
    var i = 0
    while (i < s.length) {
      val c = s.charAt(i)
      if (c == '\\') b.append("\\\\")
      else if (c == ' ' && spaces) b.append("\\s")
      else if (Character.isHighSurrogate(c) && i + 1 < s.length && Character.isLowSurrogate(s.charAt(i + 1))) {
        b.append(c).append(s.charAt(i + 1))
        i += 1
      }
      // Control characters would end or garble the line; lone surrogates have no UTF-8 form.
      else if (c < 0x20 || c == 0x7f || Character.isSurrogate(c)) b.append(f"\\u${c.toInt}%04x")
      else b.append(c)
      i += 1
    }
    b.toString
  }

  /** Undoes [[escapeWord]] and [[escapeText]]; a message when the text has a broken escape or a raw control character.
    * What it gives back is what was sent, control characters included (a robot's role may hold an escape sequence):
    * whatever shows it on a terminal passes it through [[naogateway.api.Printable.text]] first, as robotctl does.
    */
  def unescape(s: String): Either[String, String] = {
    val b = new java.lang.StringBuilder(s.length)
    var i = 0
    var error: String = null
    while (i < s.length && error == null) {
      val c = s.charAt(i)
      if (c == '\\') {
        if (i + 1 >= s.length) error = "a lone \\ at the end"
        else
          s.charAt(i + 1) match {
            case '\\' => b.append('\\'); i += 2
            case 's'  => b.append(' '); i += 2
            case 'u' if i + 6 <= s.length && s.substring(i + 2, i + 6).forall(h => Character.digit(h, 16) >= 0) =>
              b.append(Integer.parseInt(s.substring(i + 2, i + 6), 16).toChar); i += 6
            case other => error = s"unknown escape \\${printable(other.toString)}"
          }
      } else if (c < 0x20 || c == 0x7f) error = f"raw control character 0x${c.toInt}%02x"
      else { b.append(c); i += 1 }
    }
    if (error == null) Right(b.toString) else Left(error)
  }

  /** The UTF-8 length of `s`, as it travels. */
  def utf8Length(s: String): Int = s.getBytes(StandardCharsets.UTF_8).length

  // Echoes of bad input, safe to put in an error line or a log.
  private def printable(s: String): String = escapeText(s)
}
