package robotmiddleware.cluster

import java.nio.charset.StandardCharsets
import java.nio.file.{Files, Path, Paths}
import java.security.KeyStore
import java.util.concurrent.TimeUnit

import scala.jdk.CollectionConverters._

import com.typesafe.config.{Config, ConfigFactory, ConfigValueFactory}

/** The team's key store and trust store, and a stranger's, made with the JDK's keytool by the commands of
  * docs/cluster.md (passwords through the environment, as there), in a directory of the test's.
  */
object TeamKeys {

  /** The JDK's keytool beside the running JVM, if it has one. */
  val keytool: Option[Path] =
    Some(Paths.get(sys.props("java.home"), "bin", "keytool")).filter(Files.isExecutable)

  /** A node's two files and their passwords. */
  final case class Stores(keyStore: Path, keyStorePassword: String, trustStore: Path, trustStorePassword: String) {

    /** The node's `robotmiddleware.cluster.tls` settings for these files. */
    def config: Config =
      Map(
        "key-store" -> keyStore.toString,
        "key-store-password" -> keyStorePassword,
        "trust-store" -> trustStore.toString,
        "trust-store-password" -> trustStorePassword
      ).foldLeft(ConfigFactory.empty()) { case (c, (k, v)) =>
        c.withValue(s"${ClusterTls.ConfigPath}.$k", ConfigValueFactory.fromAnyRef(v))
      }
  }

  /** The team's files and its certificate (the file `team.crt` a stranger may capture: it is sent in every handshake).
    */
  final case class Team(stores: Stores, certificate: Path)

  private val KeyPassword = "ROBOTS_TLS_KEY_STORE_PASSWORD"
  private val TrustPassword = "ROBOTS_TLS_TRUST_STORE_PASSWORD"

  // The distinguished name of docs/cluster.md; the stranger copies it, which must not help.
  private val Name = "CN=naogateway team"

  /** Runs keytool in `dir` with the two password variables set; throws with its output if it fails. */
  private def run(tool: Path, dir: Path, passwords: (String, String), args: String*): Unit = {
    val pb = new ProcessBuilder((tool.toString +: args).asJava).directory(dir.toFile).redirectErrorStream(true)
    pb.environment().put(KeyPassword, passwords._1)
    pb.environment().put(TrustPassword, passwords._2)
    val p = pb.start()
    p.getOutputStream.close()
    val out = new String(p.getInputStream.readAllBytes(), StandardCharsets.UTF_8)
    if (!p.waitFor(60, TimeUnit.SECONDS)) { p.destroyForcibly(); throw new IllegalStateException("keytool hung") }
    if (p.exitValue() != 0) throw new IllegalStateException(s"keytool ${args.head} failed: $out")
  }

  /** docs/cluster.md's first command: an EC key pair under the team's name in `keyStore` (team and stranger alike). */
  private def keyPair(tool: Path, dir: Path, passwords: (String, String), keyStore: String): Unit =
    run(
      tool,
      dir,
      passwords,
      "-genkeypair",
      "-alias",
      "team",
      "-keyalg",
      "EC",
      "-groupname",
      "secp256r1",
      "-validity",
      "730",
      "-dname",
      Name,
      "-storetype",
      "PKCS12",
      "-keystore",
      keyStore,
      "-storepass:env",
      KeyPassword
    )

  /** The team's files in `dir`, made by docs/cluster.md's three commands. */
  def team(tool: Path, dir: Path, keyStorePassword: String, trustStorePassword: String): Team = {
    val passwords = (keyStorePassword, trustStorePassword)
    keyPair(tool, dir, passwords, "team-keystore.p12")
    run(tool, dir, passwords, "-exportcert", "-alias", "team", "-rfc", "-file", "team.crt", "-keystore",
      "team-keystore.p12", "-storepass:env", KeyPassword)
    run(
      tool,
      dir,
      passwords,
      "-importcert",
      "-noprompt",
      "-alias",
      "team",
      "-file",
      "team.crt",
      "-storetype",
      "PKCS12",
      "-keystore",
      "team-truststore.p12",
      "-storepass:env",
      TrustPassword
    )
    Team(Stores(dir.resolve("team-keystore.p12"), keyStorePassword, dir.resolve("team-truststore.p12"),
        trustStorePassword), dir.resolve("team.crt"))
  }

  /** A stranger's files in `dir`: a key pair of its own under the team's name, and a trust store holding the team's
    * captured certificate (so the stranger itself accepts the gateway) beside its own (so its files pass every check a
    * team node makes of its own): everything but the team's private key.
    */
  def stranger(tool: Path, dir: Path, teamCertificate: Path, password: String): Stores = {
    val passwords = (password, password)
    keyPair(tool, dir, passwords, "stranger-keystore.p12")
    run(
      tool,
      dir,
      passwords,
      "-importcert",
      "-noprompt",
      "-alias",
      "team",
      "-file",
      teamCertificate.toString,
      "-storetype",
      "PKCS12",
      "-keystore",
      "stranger-truststore.p12",
      "-storepass:env",
      TrustPassword
    )
    val keys = load(dir.resolve("stranger-keystore.p12"), password)
    val trust = load(dir.resolve("stranger-truststore.p12"), password)
    trust.setCertificateEntry("stranger", keys.getCertificate("team"))
    val out = Files.newOutputStream(dir.resolve("stranger-truststore.p12"))
    try trust.store(out, password.toCharArray)
    finally out.close()
    Stores(dir.resolve("stranger-keystore.p12"), password, dir.resolve("stranger-truststore.p12"), password)
  }

  private def load(path: Path, password: String): KeyStore = {
    val store = KeyStore.getInstance(KeyStore.getDefaultType)
    val in = Files.newInputStream(path)
    try store.load(in, password.toCharArray)
    finally in.close()
    store
  }
}
