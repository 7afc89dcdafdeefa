package naogateway.launcher

import scala.util.control.NonFatal

import com.typesafe.config.{Config, ConfigFactory}

import naogateway.wire.SigningKey

/** `robotctl keys <id>...` (docs/protocol.md 6.7): each robot's key, derived from the team key, for a team to build or
  * flash that robot with. An object of its own so that only this command loads the config library.
  */
object RobotKeys {

  /** The config path of the team key, as the gateway reads it. */
  val KeyPath = "naogateway.signing.key"

  /** Prints one line per robot id, `robot <id> key <64 hex digits>`. The team key comes from where the gateway reads
    * it: the config file (`--config`), else application.conf, else the environment variable; it is never printed, and a
    * bad one is refused naming its length only. Returns robotctl's exit code.
    */
  def run(args: Seq[String], env: String => Option[String], out: String => Unit, err: String => Unit,
      application: => Config = ConfigFactory.defaultApplication()): Int = {
    val (file, ids) = args.toList match {
      case "--config" :: f :: rest => (Some(f), rest)
      case rest                    => (None, rest)
    }
    val robots = ids.map(id => id.toIntOption.filter(_ >= 0).toRight(s"robot id '$id' is not a robot id"))
    if (ids.isEmpty || ids.exists(_.startsWith("--"))) { err(RobotCtl.KeysUsage); RobotCtl.ExitUsage }
    else
      robots.collectFirst { case Left(problem) => problem } match {
        case Some(problem) => err(s"robotctl keys: $problem"); RobotCtl.ExitUsage
        case None =>
          teamKey(file, env, application) match {
            case Left(problem) => err(s"robotctl keys: $problem"); RobotCtl.ExitFailed
            case Right(team) =>
              robots.collect { case Right(id) => id }.foreach(id => out(s"robot $id key ${team.robotKey(id).toHex}"))
              RobotCtl.ExitOk
          }
      }
  }

  /** The team key as the gateway reads it: [[KeyPath]] of the file or application.conf, else the environment. */
  private def teamKey(
      file: Option[String], env: String => Option[String], application: => Config): Either[String, SigningKey] = {
    val variable = RobotCtl.TeamKeyVariable
    val configured =
      try {
        val c = Launcher.config(file.toSeq).withFallback(application)
        Right(if (c.hasPath(KeyPath)) c.getString(KeyPath).trim else "")
      } catch { case NonFatal(e) => Left(s"config: ${e.getMessage}") }
    configured.flatMap { fromConfig =>
      val hex = if (fromConfig.nonEmpty) fromConfig else env(variable).getOrElse("").trim
      if (hex.isEmpty) Left(s"no team key: set $KeyPath in the config or the environment variable $variable")
      else SigningKey.fromHex(hex).left.map(e => s"$KeyPath ($variable): $e")
    }
  }
}
