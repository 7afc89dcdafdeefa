package naogateway.launcher

import java.io.{BufferedInputStream, ByteArrayOutputStream, IOException, InputStream}
import java.net.{ConnectException, InetSocketAddress, Socket, SocketTimeoutException, UnknownHostException}
import java.nio.charset.StandardCharsets

import scala.util.control.NonFatal

import apps.control.ControlProtocol
import apps.control.ControlProtocol.Answer
import naogateway.api.Printable
import naogateway.wire.RpcValue

/** `bin/robotctl` (or `./sbt "robotctl status"`): a command-line client of a running gateway's control port
  * (apps.control.ControlServer). It starts no actor system and loads no Akka, so it answers within about a second.
  */
object RobotCtl {

  /** What robotctl was asked to do. */
  type Request = ControlProtocol.Request

  /** The parsed command lines. */
  val Request: ControlProtocol.Request.type = ControlProtocol.Request

  /** The exit codes: done, failed (the gateway said no, or is not there), and a wrong command line. */
  val ExitOk = 0
  val ExitFailed = 1
  val ExitUsage = 2

  /** Time to reach the control port; it is on this machine, so a gateway that is there answers at once. */
  val ConnectTimeoutMillis = 2000

  /** Longest silence while waiting for the answer, above the server's own answer-timeout (a watch adds its seconds). */
  val ReadTimeoutMillis = 30000

  /** The help of `robotctl keys` ([[RobotKeys]]). */
  val KeysUsage: String =
    """usage: robotctl keys [--config config-file] <robotId> ...
      |  each robot's key, derived from the team key of naogateway.signing.key / $NAOGATEWAY_SIGNING_KEY,
      |  to build or flash that robot with (protocol.md 6.7)""".stripMargin

  /** The environment variable the gateway reads its team key from (naogateway's reference.conf). */
  val TeamKeyVariable = "NAOGATEWAY_SIGNING_KEY"

  /** The command line's help: the control port's commands, and `keys`, which needs no gateway. */
  val usage: String = ControlProtocol.usage + "\n" + KeysUsage

  /** Reads a parameter: a number, a truth value or a text. */
  def param(text: String): RpcValue = ControlProtocol.param(text)

  /** Parses the command (without `--control`); a clear message when it is wrong. */
  def parse(args: Seq[String]): Either[String, Request] =
    ControlProtocol.parse(args).left.map(m => if (m == ControlProtocol.usage) usage else m)

  /** The control port's `host:port` (from `--control`, else `env(NAOGATEWAY_CONTROL)`, else the default) and the
    * request.
    */
  def invocation(args: Seq[String], env: String => Option[String]): Either[String, (String, Request)] = {
    val (address, rest) = args.toList match {
      case "--control" :: a :: more                        => (Some(a), more)
      case "--control" :: Nil                              => (Some(""), Nil)
      case first :: more if first.startsWith("--control=") => (Some(first.stripPrefix("--control=")), more)
      case other                                           => (None, other)
    }
    parse(rest).map(address.orElse(env(ControlProtocol.AddressVariable)).getOrElse(ControlProtocol.DefaultAddress) -> _)
  }

  /** Runs one command: sends it to the control port and hands each output line to `out` as it arrives, and errors to
    * `err`. Returns the exit code.
    */
  def run(args: Seq[String], env: String => Option[String], out: String => Unit, err: String => Unit): Int =
    // `keys` needs no gateway, and its own object: only it loads the config library (robotctl's start stays light).
    if (args.headOption.contains("keys")) RobotKeys.run(args.drop(1), env, out, err)
    else invocation(args, env) match {
      case Left(message) =>
        err(message)
        ExitUsage
      case Right((address, request)) =>
        ControlProtocol.address(address) match {
          case Left(message) =>
            err(s"robotctl: --control / ${ControlProtocol.AddressVariable}: $message")
            ExitUsage
          case Right((host, port)) =>
            val line = ControlProtocol.render(request)
            if (ControlProtocol.utf8Length(line) > ControlProtocol.MaxRequestBytes) {
              err(s"robotctl: the command is longer than ${ControlProtocol.MaxRequestBytes} bytes")
              ExitUsage
            } else {
              val readTimeout = request match {
                case ControlProtocol.Request.Watch(_, seconds) => ReadTimeoutMillis + seconds.toLong * 1000
                case _                                         => ReadTimeoutMillis.toLong
              }
              val noGateway: String => Int = request match {
                // No gateway to ask: the doctor checks the machine against the config the gateway would start with.
                case ControlProtocol.Request.Doctor(file) => where => offlineDoctor(where, file, out, err)
                case _ => where => { err(s"no gateway at $where: is naogateway running?"); ExitFailed }
              }
              exchange(host, port, line, math.min(readTimeout, Int.MaxValue.toLong).toInt, out, err, noGateway)
            }
        }
    }

  private def exchange(host: String, port: Int, request: String, readTimeout: Int, out: String => Unit,
      err: String => Unit,
      noGateway: String => Int): Int = {
    val where = s"$host:$port"
    val socket = new Socket()
    try {
      socket.connect(new InetSocketAddress(host, port), ConnectTimeoutMillis)
      socket.setSoTimeout(readTimeout)
      socket.getOutputStream.write((request + "\n").getBytes(StandardCharsets.UTF_8))
      socket.getOutputStream.flush()
      val in = new BufferedInputStream(socket.getInputStream)
      def next(): Int =
        readLine(in) match {
          case None => err(s"robotctl: the gateway at $where closed the connection without an answer"); ExitFailed
          case Some(Left(problem)) => err(s"robotctl: $problem"); ExitFailed
          case Some(Right(text))   =>
            // The wire's escapes undone give back what the gateway sent, robots' strings included: their control
            // characters are shown escaped, so no escape sequence reaches the terminal.
            ControlProtocol.readAnswer(text) match {
              case Right(Answer.Line(l))  => out(Printable.text(l)); next()
              case Right(Answer.Ok(t))    => if (t.nonEmpty) out(Printable.text(t)); ExitOk
              case Right(Answer.Error(t)) => err(s"robotctl: ${Printable.text(t)}"); ExitFailed
              case Left(problem) => err(s"robotctl: the gateway at $where answered oddly: $problem"); ExitFailed
            }
        }
      next()
    } catch {
      case _: ConnectException | _: SocketTimeoutException if !socket.isConnected =>
        noGateway(where)
      case _: SocketTimeoutException =>
        err(s"robotctl: no answer from the gateway at $where within ${readTimeout / 1000} s")
        ExitFailed
      case e: UnknownHostException =>
        err(s"robotctl: unknown host ${e.getMessage}")
        ExitFailed
      case e: IOException =>
        err(s"robotctl: connection to the gateway at $where failed: ${e.getMessage}")
        ExitFailed
    } finally {
      try socket.close()
      catch { case NonFatal(_) => () }
    }
  }

  /** `robotctl doctor` without a running gateway: that is the first problem, and the machine is checked against the
    * config the launcher would read (`configFile`, application.conf, the demo's defaults): the config itself, keys no
    * reference knows, the demo's loopback addresses, ports held by other programs, the recording directory.
    */
  def offlineDoctor(where: String, configFile: Option[String], out: String => Unit, err: String => Unit,
      probe: Preflight.PortUse => Preflight.Probe = Preflight.probe): Int = {
    import apps.control.Finding
    val gateway = Finding(
      "gateway",
      s"no gateway answers at $where",
      problem = true,
      s"start it (bin/naogateway ${configFile.getOrElse("[robots.conf]")}), or give its control port with --control"
    )
    val machine: Vector[Finding] =
      try {
        val c = Launcher.nodeConfig(Launcher.config(configFile.toSeq))
        Preflight.validate(c)
        val keys = Doctor.configFindings(Preflight.unknownKeys(c, Preflight.knownKeys))
        val loopback = Preflight.missingLoopback(c.getInt("apps.launcher.simulated-robots")).toVector
          .map(l => Finding("demo addresses", l, problem = true, "see the text"))
        val ports = Preflight.portProblems(Preflight.ports(c), probe)
        val portFindings =
          if (ports.isEmpty) Vector(Finding("ports", "every port the gateway binds is free", problem = false))
          else
            ports.map(p => Finding("ports", p.split("; ").head, problem = true, p.split("; ").drop(1).mkString("; ")))
        val settings = naogateway.gateway.GatewaySettings.fromConfig(c.getConfig("naogateway"))
        val disk =
          Option.when(settings.recording.enabled)(Doctor.disk(settings.recording.directory)).toVector.flatMap { d =>
            Doctor.recordingFindings(naogateway.gateway.recording.Recording.Off.stats, Some(d))
          }
        val config = Finding("config",
          configFile.fold("the demo's defaults (no file given)")(f => s"$f reads without error"), problem = false)
        config +: (keys ++ loopback ++ portFindings ++ disk) :+ Doctor.clusterFinding(c)
      } catch {
        case e: Exception if Preflight.problem(e).isDefined =>
          Vector(Finding("config", Preflight.problem(e).get.stripPrefix("config: "), problem = true,
              "correct the key named"))
      }
    val all = gateway +: machine
    all.foreach(f => out(f.line))
    err(s"robotctl: ${all.count(_.problem)} problem(s), each with its fix above")
    ExitFailed
  }

  /** The next line of `in` (without its `\n`), None at the end of the stream; a line longer than the protocol allows is
    * refused rather than read into memory without bound.
    */
  private def readLine(in: InputStream): Option[Either[String, String]] = {
    val buffer = new ByteArrayOutputStream(128)
    var b = in.read()
    if (b < 0) None
    else {
      while (b >= 0 && b != '\n' && buffer.size() <= ControlProtocol.MaxAnswerBytes) {
        buffer.write(b)
        b = in.read()
      }
      if (buffer.size() > ControlProtocol.MaxAnswerBytes)
        Some(Left(s"an answer line is longer than ${ControlProtocol.MaxAnswerBytes} bytes"))
      else if (b < 0) None
      else Some(Right(new String(buffer.toByteArray, StandardCharsets.UTF_8)))
    }
  }

  def main(args: Array[String]): Unit = {
    val code = run(args.toSeq, name => Option(System.getenv(name)), line => System.out.println(line),
      line => System.err.println(line))
    System.out.flush()
    System.exit(code)
  }
}
