package apps

import java.io.File

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** Guards the Apache-licensed Akka line: the BSL releases stop an actor system after 15 minutes without a key. */
class LicenceGuardSpec extends AnyWordSpec with Matchers {

  private val licenceCheck = "akka.actor.dungeon.LicenseKeySupplier"

  private def akkaJars: Seq[File] =
    System.getProperty("java.class.path").split(File.pathSeparator).toSeq.map(new File(_))
      .filter(f => f.getName.startsWith("akka-") && f.getName.endsWith(".jar"))

  // Akka HTTP's jars carry their own version line (10.2.x for Akka 2.6), not Akka's.
  private def httpJar(name: String): Boolean = name.startsWith("akka-http") || name.startsWith("akka-parsing")

  "The runtime classpath" should {
    "not carry Akka's licence-key check" in {
      val loader = getClass.getClassLoader
      loader.getResource(licenceCheck.replace('.', '/') + ".class") shouldBe null
      an[ClassNotFoundException] should be thrownBy Class.forName(licenceCheck, false, loader)
    }

    "run Akka 2.6, the last release line under the Apache License 2.0" in {
      akka.Version.current should startWith("2.6.")
    }

    "hold every Akka jar at that one version" in {
      val jars = akkaJars.filterNot(j => httpJar(j.getName))
      jars should not be empty
      all(jars.map(_.getName)) should include(s"_2.13-${akka.Version.current}.jar")
    }

    "hold Akka HTTP at 10.2, its release line for Akka 2.6 under the Apache License 2.0" in {
      val jars = akkaJars.filter(j => httpJar(j.getName))
      jars.map(_.getName.takeWhile(_ != '_')).toSet should contain allOf ("akka-http", "akka-http-core", "akka-parsing")
      all(jars.map(_.getName)) should include("_2.13-10.2.")
    }
  }
}
