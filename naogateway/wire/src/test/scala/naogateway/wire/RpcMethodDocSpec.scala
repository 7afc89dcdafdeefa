package naogateway.wire

import java.nio.charset.StandardCharsets.UTF_8
import java.nio.file.{Files, Path, Paths}

import scala.jdk.CollectionConverters._

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** The method table in code and the one in docs/protocol.md (section 7) name the same methods the same way. */
class RpcMethodDocSpec extends AnyWordSpec with Matchers {

  // Forked tests run in the module folder (naogateway/), an sbt shell in the checkout.
  private val doc: Vector[String] = Seq(Paths.get("../../docs/protocol.md"), Paths.get("docs/protocol.md"))
    .find(Files.isRegularFile(_))
    .map((p: Path) => Files.readAllLines(p, UTF_8).asScala.toVector)
    .getOrElse(fail("docs/protocol.md not found"))

  private def section(heading: String): Vector[String] =
    doc.dropWhile(_.trim != heading).drop(1).takeWhile(l => !l.startsWith("## ") && !l.startsWith("### "))

  private val Name = """`([a-z]+)\.([a-zA-Z]+)`""".r

  "RpcMethod.all" should {
    "list exactly the methods of protocol.md 7.2, in its order" in {
      val documented = section("### 7.2 Methods").filter(_.startsWith("| `")).map { row =>
        Name.findFirstMatchIn(row).map(m => m.group(1) + "." + m.group(2)).getOrElse(fail(s"no method in: $row"))
      }
      documented should not be empty
      RpcMethod.all.map(_.name) shouldBe documented
    }
    "call again exactly the methods protocol.md 7.1 names as safe to call again" in {
      val row =
        section("### 7.1 Rules").find(_.startsWith("| new call, new `callId`")).getOrElse(fail("no retry rule in 7.1"))
      val again = Name.findAllMatchIn(row).map(m => m.group(1) + "." + m.group(2)).toSet
      again should not be empty
      RpcMethod.all.filter(_.idempotent).map(_.name).toSet shouldBe again
    }
    "find every method by its module and method, and nothing else" in {
      RpcMethod.all.foreach(m => RpcMethod.find(m.module, m.method) shouldBe Some(m))
      RpcMethod.find("heartbeat", "probe") shouldBe None
      RpcMethod.all.map(_.name).distinct should have size RpcMethod.all.size.toLong
    }
  }
}
