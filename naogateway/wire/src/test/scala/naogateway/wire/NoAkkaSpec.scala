package naogateway.wire

import java.io.File

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** The wire layer is pure: the build keeps Akka off its classpath, and this spec fails the day it comes back. */
class NoAkkaSpec extends AnyWordSpec with Matchers {

  private val loader = getClass.getClassLoader

  "The wire module's classpath" should {
    "not hold Akka's typed actor system" in {
      an[ClassNotFoundException] should be thrownBy Class.forName("akka.actor.typed.ActorSystem", false, loader)
    }

    "not hold any Akka class or jar" in {
      loader.getResource("akka/actor/ActorSystem.class") shouldBe null
      val jars = System.getProperty("java.class.path").split(File.pathSeparator).toSeq.map(new File(_).getName)
      jars.filter(_.startsWith("akka-")) shouldBe empty
    }

    "still hold the wire code and the protobuf classes it is built on" in {
      Class.forName("naogateway.wire.stream.SecureStream", false, loader).getName shouldBe "naogateway.wire.stream.SecureStream"
      Class.forName("naogateway.proto.Message", false, loader).getName shouldBe "naogateway.proto.Message"
    }
  }
}
