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
      val jars = akkaJars
      jars should not be empty
      all(jars.map(_.getName)) should include(s"_2.13-${akka.Version.current}.jar")
    }
  }
}
