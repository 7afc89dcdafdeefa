package naogateway.testkit

import com.typesafe.config.{Config, ConfigFactory}
import org.scalatest.matchers.should.Matchers

/** The settings specs' one shape: a module's settings read from its configuration with a few keys overridden, and the
  * bad values each spec lists as a table of overrides and what each must be refused with.
  */
trait SettingsTables { this: Matchers =>

  /** `read` over the configuration at `path` of `base` (the loaded configuration unless given), `overrides` first. */
  def overriding[S](path: String, base: => Config = ConfigFactory.load())(read: Config => S)(overrides: String): S =
    read(ConfigFactory.parseString(overrides).withFallback(base.getConfig(path)))

  /** Each `overrides -> message`: reading those overrides throws an IllegalArgumentException with exactly `message`. */
  def refusesWith(read: String => Any)(table: (String, String)*): Unit =
    table.foreach { case (overrides, message) =>
      withClue(s"[$overrides] ") { the[IllegalArgumentException] thrownBy read(overrides) should have message message }
    }

  /** Each of `overrides`: reading it throws an IllegalArgumentException, whatever its message. */
  def refuses(read: String => Any)(overrides: String*): Unit =
    overrides.foreach { o => withClue(s"[$o] ") { an[IllegalArgumentException] should be thrownBy read(o) } }

  /** The message of the IllegalArgumentException reading `overrides` throws, for checks on what it says. */
  def messageOf(read: String => Any)(overrides: String): String =
    intercept[IllegalArgumentException](read(overrides)).getMessage
}
