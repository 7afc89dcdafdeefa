package style

import java.nio.charset.StandardCharsets.UTF_8
import java.nio.file.{Files, Paths}

import scala.jdk.CollectionConverters._
import scala.util.Try

import com.typesafe.config.{
  Config,
  ConfigFactory,
  ConfigResolveOptions,
  ConfigValue,
  ConfigValueFactory,
  ConfigValueType
}
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** The settings tables of the docs against the reference.conf files they describe: every key a reference defines is in
  * a table, every key a table names exists, and the default a table gives is the reference's. The tables are the
  * operators' reference (docs/configuration.md and the settings of the web view, the control port and the ZeroMQ
  * doors), so a key added, renamed or given a new default without its row fails here.
  */
class ConfigReferenceSpec extends AnyWordSpec with Matchers {

  /** The documents whose `| key | …` tables describe settings. */
  private val Documents = Seq("docs/configuration.md", "docs/zeromq.md", "docs/web.md", "docs/robotctl.md")

  /** The configuration roots the project's reference.conf files define. */
  private val Roots = Seq("naogateway", "robotmiddleware", "apps")

  /** Every reference.conf of the classpath (the gateway's, the middleware's, the apps'), resolved without the
    * environment, so an operator's `NAOGATEWAY_…` variable does not change the defaults compared.
    */
  private val reference: Config =
    ConfigFactory.parseResources("reference.conf").resolve(ConfigResolveOptions.noSystem())

  /** One row of a settings table: the keys it names (full paths; `p.*` covers every key under p) and the default tokens
    * of its second column (empty when the column does not start with one, as `thread pool, 1 thread`).
    */
  private final case class Row(document: String, line: Int, keys: Seq[String], defaults: Seq[String]) {
    def where: String = s"$document:$line"
  }

  private val Backticked = "`([^`]*)`".r

  /** The rows of the document's settings tables: a table is one whose header's first cell is `key`; a row's keys are
    * relative to the config path in backticks of the heading above it, unless they start with a root themselves.
    */
  private def rows(document: String): Seq[Row] = {
    val lines = Files.readAllLines(Paths.get(document), UTF_8).asScala.toVector
    var base = Option.empty[String]
    var inTable = false
    val found = Vector.newBuilder[Row]
    lines.zipWithIndex.foreach { case (line, index) =>
      if (line.startsWith("#")) {
        base = Backticked.findFirstMatchIn(line).map(_.group(1)).filter(p =>
          Roots.exists(r => p == r || p.startsWith(r + ".")))
        inTable = false
      } else if (!line.startsWith("|")) inTable = false
      else {
        val cells = line.split("\\|", -1).map(_.trim).drop(1)
        if (cells.headOption.contains("key")) inTable = true
        else if (inTable && cells.length >= 2 && cells(0).startsWith("`")) {
          val named = Backticked.findAllMatchIn(cells(0)).map(_.group(1)).toVector
          val absolute = named.foldLeft(Vector.empty[String]) { (keys, key) =>
            if (key.startsWith(".") && keys.nonEmpty) keys :+ (keys.head.substring(0, keys.head.lastIndexOf('.')) + key)
            else if (Roots.exists(r => key.startsWith(r + "."))) keys :+ key
            else keys :+ base.fold(key)(b => s"$b.$key")
          }
          val defaults =
            if (cells(1).startsWith("`")) Backticked.findAllMatchIn(cells(1)).map(_.group(1)).toVector else Vector.empty
          found += Row(document, index + 1, absolute, defaults)
        }
      }
    }
    found.result()
  }

  private lazy val documented: Seq[Row] = Documents.flatMap(rows)

  /** The leaf keys the references define under the project's roots. */
  private lazy val leaves: Seq[String] =
    Roots.filter(reference.hasPath).flatMap(r => reference.getConfig(r).entrySet.asScala.map(e => s"$r.${e.getKey}"))

  private def covers(documentedKey: String, key: String): Boolean =
    if (documentedKey.endsWith(".*")) key.startsWith(documentedKey.dropRight(1))
    else key == documentedKey || key.startsWith(documentedKey + ".")

  /** A default as the docs write it, compared with the reference's value of the same type. */
  private def sameDefault(written: String, value: ConfigValue): Boolean = {
    val text = written.stripPrefix("\"").stripSuffix("\"")
    value.valueType match {
      case ConfigValueType.BOOLEAN =>
        Set("on", "true", "yes").contains(text) == value.unwrapped.asInstanceOf[java.lang.Boolean].booleanValue &&
        Set("on", "off", "true", "false", "yes", "no").contains(text)
      case ConfigValueType.NUMBER =>
        Try(BigDecimal(text) == BigDecimal(value.unwrapped.toString)).getOrElse(false)
      case ConfigValueType.STRING => text == value.unwrapped.toString
      case ConfigValueType.LIST   => text.replace(" ", "") == value.render().replace(" ", "")
      case _                      => true
    }
  }

  "The settings tables" should {
    "be found, so that a renamed heading or table cannot empty this check" in {
      leaves.size should be > 150
      documented.size should be > 100
      Roots.foreach(r => withClue(r)(documented.exists(_.keys.exists(_.startsWith(r + "."))) shouldBe true))
    }

    "list every key of the reference.conf files" in {
      val missing = leaves.filterNot(key => documented.exists(_.keys.exists(covers(_, key)))).sorted
      withClue(s"keys with no row in ${Documents.mkString(", ")}: ") { missing shouldBe empty }
    }

    "name only keys the reference.conf files define" in {
      val unknown = for {
        row <- documented
        key <- row.keys
        path = key.stripSuffix(".*")
        if !Try(reference.hasPathOrNull(path)).getOrElse(false)
      } yield s"${row.where} $key"
      unknown shouldBe empty
    }

    "tell a default written differently from the reference's value" in {
      val parsed = ConfigFactory.parseString("n = 11011, d = 10.0, b = on, s = 200ms, q = \"0.0.0.0\", l = []")
      Seq("11011" -> "n", "10.0" -> "d", "on" -> "b", "200ms" -> "s", "\"0.0.0.0\"" -> "q", "[]" -> "l").foreach {
        case (written, key) => withClue(key)(sameDefault(written, parsed.getValue(key)) shouldBe true)
      }
      Seq("11012" -> "n", "1.0" -> "d", "off" -> "b", "2s" -> "s", "0.0.0.1" -> "q", "[1]" -> "l").foreach {
        case (written, key) => withClue(key)(sameDefault(written, parsed.getValue(key)) shouldBe false)
      }
      sameDefault("anything", ConfigValueFactory.fromAnyRef(java.util.Map.of("a", 1))) shouldBe true
    }

    "give each key the reference's default" in {
      val wrong = for {
        row <- documented
        if row.defaults.nonEmpty && !row.keys.exists(_.endsWith(".*"))
        (key, written) <- row.keys.zip(row.defaults)
        if reference.hasPath(key) && reference.getValue(key).valueType != ConfigValueType.OBJECT
        value = reference.getValue(key)
        if !sameDefault(written, value)
      } yield s"${row.where} $key: the table says `$written`, reference.conf ${value.render()}"
      wrong shouldBe empty
    }
  }
}
