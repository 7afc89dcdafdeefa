package naogateway.wire.gamecontroller

import java.io.InputStream

/** Test access to the real GameController packets kept in this module's test resources (vectors/gamecontroller). */
object GameControllerVectors {

  /** The resource folder the vectors live in, with their README and provenance. */
  val Folder = "/vectors/gamecontroller/"

  /** The bytes of vector `file`; a missing vector is a defect of the checkout, so it throws rather than cancels. */
  def bytes(file: String): Array[Byte] = {
    val in: InputStream = getClass.getResourceAsStream(Folder + file)
    if (in == null)
      throw new IllegalStateException(s"GameController vector $file is not on the test classpath ($Folder)")
    try in.readAllBytes()
    finally in.close()
  }

  /** The README's text, which the vector specs check the packets against. */
  def readme: String = new String(bytes("README.md"), java.nio.charset.StandardCharsets.UTF_8)
}
