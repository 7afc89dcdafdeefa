package naogateway.wire

import java.net.URLClassLoader

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** The method table must come up whichever of its entries a program touches first (a fresh class loader for each). */
class RpcMethodInitSpec extends AnyWordSpec with Matchers {

  /** A loader of its own for the table's classes, so their initialisation runs again, in the order a test picks. */
  private def freshLoader(): URLClassLoader =
    new URLClassLoader(Array(classOf[RpcMethod].getProtectionDomain.getCodeSource.getLocation),
      getClass.getClassLoader) {
      override def loadClass(name: String, resolve: Boolean): Class[_] =
        if (name.startsWith("naogateway.wire.RpcMethod")) getClassLoadingLock(name).synchronized {
          Option(findLoadedClass(name)).getOrElse(findClass(name))
        }
        else super.loadClass(name, resolve)
    }

  "The method table" should {
    "initialise when any one of its methods is the first thing touched" in {
      RpcMethod.all.map(_.productPrefix).foreach { first =>
        val loader = freshLoader()
        try {
          val entry = loader.loadClass(s"naogateway.wire.RpcMethod$$$first$$").getField("MODULE$").get(null)
          val table = loader.loadClass("naogateway.wire.RpcMethod$").getField("MODULE$").get(null)
          val all = table.getClass.getMethod("all").invoke(table).asInstanceOf[Vector[AnyRef]]
          withClue(s"$first first: ") {
            all should contain(entry)
            all.count(_ == null) shouldBe 0
            all.size shouldBe RpcMethod.all.size
          }
        } finally loader.close()
      }
    }
  }
}
