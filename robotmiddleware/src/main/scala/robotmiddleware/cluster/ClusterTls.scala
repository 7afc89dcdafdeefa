package robotmiddleware.cluster

import java.nio.file.{Files, Path, Paths}
import java.security.KeyStore
import java.security.cert.X509Certificate

import scala.jdk.CollectionConverters._
import scala.util.Try
import scala.util.control.NonFatal

import akka.actor.AddressFromURIString
import com.typesafe.config.{Config, ConfigFactory, ConfigValueFactory}

/** Whether a cluster node may talk plain TCP or must run Artery over TLS with the team's key store and trust store
  * (docs/cluster.md), decided from its config before it starts. Anyone who reaches a node's port can join the cluster
  * and command the robots, so a node whose addresses are not all on loopback starts only with TLS, and TLS requires
  * every peer to present a certificate of the team's trust store.
  */
object ClusterTls {

  /** Where the TLS settings live. */
  val ConfigPath: String = "robotmiddleware.cluster.tls"

  /** A password from the config or the environment: `toString` hides it, so no log line or error can show it. */
  final class Password(value: String) {

    /** The password, for the key store API. */
    def chars: Array[Char] = value.toCharArray

    /** Whether none was given. */
    def isEmpty: Boolean = value.isEmpty

    /** The password for Akka's own settings, which read it from the config. */
    private[cluster] def reveal: String = value

    override def toString: String = "Password(hidden)"

    override def equals(other: Any): Boolean = other match {
      case p: Password => p.reveal == value
      case _           => false
    }

    override def hashCode: Int = value.hashCode
  }

  /** The team's two files, the passwords that open them, and the TLS version and cipher suites every node uses. */
  final case class TeamStores(keyStore: Path, keyStorePassword: Password, trustStore: Path,
      trustStorePassword: Password, protocol: String, algorithms: Vector[String])

  /** How a node's cluster traffic travels. */
  sealed trait Transport extends Product with Serializable

  /** The transports. */
  object Transport {

    /** Plain TCP: every address of the node is on loopback and no store is set. */
    case object PlainLoopback extends Transport

    /** TLS with mutual authentication: a peer without a certificate of the trust store is refused. */
    final case class Tls(stores: TeamStores) extends Transport
  }

  /** An address the node binds to, announces or joins, and the setting it comes from (for the refusal's line). */
  final case class NodeAddress(host: String, setting: String)

  /** The addresses of `c` that decide whether the node is on loopback only: its canonical and bind hostnames, and the
    * seed nodes' hosts (where it connects to).
    */
  def addresses(c: Config): Vector[NodeAddress] = {
    val cluster = "robotmiddleware.cluster"
    def named(host: String, key: String, env: String, akkaKey: String): NodeAddress =
      if (c.hasPath(s"$cluster.$key") && c.getString(s"$cluster.$key") == host)
        NodeAddress(host, s"$cluster.$key ($env)")
      else NodeAddress(host, akkaKey)
    val canonical = named(c.getString("akka.remote.artery.canonical.hostname"), "hostname", "ROBOTS_HOSTNAME",
      "akka.remote.artery.canonical.hostname")
    val bind = Option(c.getString("akka.remote.artery.bind.hostname")).filter(_.nonEmpty)
      .map(NodeAddress(_, "akka.remote.artery.bind.hostname"))
    val seeds = c.getStringList("akka.cluster.seed-nodes").asScala.toVector.map { uri =>
      // A seed that does not parse is not known to be on loopback: it counts as off.
      val host = Try(AddressFromURIString(uri).host).toOption.flatten.getOrElse(uri)
      named(host, "gateway-host", "ROBOTS_GATEWAY_HOST", "akka.cluster.seed-nodes")
    }
    (canonical +: bind.toVector) ++ seeds
  }

  private val Ipv4 = """(\d{1,3})\.(\d{1,3})\.(\d{1,3})\.(\d{1,3})""".r
  private val Ipv6Loopback = """[0:]*:0*1""".r

  /** Whether `host` is certainly a loopback address: `localhost`, 127.0.0.0/8 or ::1, written as such. Any other name
    * counts as off loopback, since what it resolves to can change (and resolving it is no pure decision).
    */
  def isLoopback(host: String): Boolean = {
    val h = host.trim.stripPrefix("[").stripSuffix("]")
    h.equalsIgnoreCase("localhost") || (h match {
      case Ipv4(a, b, c, d) => Seq(a, b, c, d).forall(_.toInt <= 255) && a.toInt == 127
      // ::1 in any of its spellings (zeros and colons, then a final 1); nothing is looked up.
      case Ipv6Loopback() => true
      case _              => false
    })
  }

  private def setting(key: String): String = s"$ConfigPath.$key"

  private val KeyStoreSetting = s"${setting("key-store")} (ROBOTS_TLS_KEY_STORE)"
  private val TrustStoreSetting = s"${setting("trust-store")} (ROBOTS_TLS_TRUST_STORE)"
  private val KeyStorePasswordSetting = s"${setting("key-store-password")} (ROBOTS_TLS_KEY_STORE_PASSWORD)"
  private val TrustStorePasswordSetting = s"${setting("trust-store-password")} (ROBOTS_TLS_TRUST_STORE_PASSWORD)"

  /** The node's transport, or one line naming the setting that stops it from starting. With the two stores set, TLS
    * (also on loopback, as the tests use it); without them, plain TCP on loopback only. `storeProblem` checks the
    * stores (the files; [[storeProblem]] in production).
    */
  def decide(c: Config, storeProblem: TeamStores => Option[String]): Either[String, Transport] = {
    val t = c.getConfig(ConfigPath)
    val keyStore = t.getString("key-store").trim
    val trustStore = t.getString("trust-store").trim
    (keyStore.isEmpty, trustStore.isEmpty) match {
      case (true, true) =>
        addresses(c).find(a => !isLoopback(a.host)) match {
          case None => Right(Transport.PlainLoopback)
          case Some(off) =>
            Left(s"${off.setting} is ${off.host}, off loopback, where anyone who reaches the cluster port could join " +
              s"and command the robots: set $KeyStoreSetting and $TrustStoreSetting to the team's files " +
              "(docs/cluster.md makes them with keytool)")
        }
      case (false, true) => Left(s"$TrustStoreSetting is not set, but the key store is: TLS needs both")
      case (true, false) => Left(s"$KeyStoreSetting is not set, but the trust store is: TLS needs both")
      case (false, false) =>
        val stores = TeamStores(
          Paths.get(keyStore),
          new Password(t.getString("key-store-password")),
          Paths.get(trustStore),
          new Password(t.getString("trust-store-password")),
          t.getString("protocol"),
          t.getStringList("enabled-algorithms").asScala.toVector
        )
        if (stores.keyStorePassword.isEmpty) Left(s"$KeyStorePasswordSetting is not set")
        else if (stores.trustStorePassword.isEmpty) Left(s"$TrustStorePasswordSetting is not set")
        else if (stores.algorithms.isEmpty) Left(s"${setting("enabled-algorithms")} is empty")
        else storeProblem(stores).toLeft(Transport.Tls(stores))
    }
  }

  /** What is wrong with the team's files, if anything: each must be a readable key store that its password opens; the
    * key store must hold a private key (which its password also opens) whose certificate the trust store trusts, so
    * that nodes made from the same two files accept each other. The line names the setting, never a password.
    */
  def storeProblem(s: TeamStores): Option[String] =
    open(s.keyStore, s.keyStorePassword, KeyStoreSetting, KeyStorePasswordSetting).flatMap { keys =>
      open(s.trustStore, s.trustStorePassword, TrustStoreSetting, TrustStorePasswordSetting).flatMap { trust =>
        val aliases = keys.aliases().asScala.toVector
        val keyAliases = aliases.filter(keys.isKeyEntry)
        val trusted = trust.aliases().asScala.toVector.filter(trust.isCertificateEntry)
        if (keyAliases.isEmpty) Left(s"$KeyStoreSetting: ${s.keyStore} holds no private key")
        else if (trusted.isEmpty) Left(s"$TrustStoreSetting: ${s.trustStore} holds no certificate to trust")
        else if (!keyAliases.forall(a => Try(keys.getKey(a, s.keyStorePassword.chars)).isSuccess))
          Left(s"$KeyStorePasswordSetting opens ${s.keyStore} but not its private key (it needs the store's password)")
        else {
          val chain = keyAliases.flatMap(a => Option(keys.getCertificateChain(a)).toVector.flatMap(_.toVector))
          val anchors = trusted.map(trust.getCertificate).collect { case x: X509Certificate => x }
          val accepted = chain.exists {
            case x: X509Certificate => anchors.contains(x) || anchors.exists(a => verifiedBy(x, a))
            case _                  => false
          }
          if (accepted) Right(())
          else
            Left(s"$TrustStoreSetting: ${s.trustStore} does not trust the certificate of ${s.keyStore}, so nodes " +
              "with these files would refuse each other: make both from the same team key (docs/cluster.md)")
        }
      }
    }.left.toOption

  private def verifiedBy(cert: X509Certificate, anchor: X509Certificate): Boolean =
    cert.getIssuerX500Principal == anchor.getSubjectX500Principal && Try(cert.verify(anchor.getPublicKey)).isSuccess

  // Loaded as Akka's ConfigSSLEngineProvider loads it (the JVM's default type), so what passes here Akka can read.
  private def open(path: Path, password: Password, fileSetting: String,
      passwordSetting: String): Either[String, KeyStore] =
    if (!Files.isRegularFile(path) || !Files.isReadable(path)) Left(s"$fileSetting: $path is not a readable file")
    else
      try {
        val store = KeyStore.getInstance(KeyStore.getDefaultType)
        val in = Files.newInputStream(path)
        try store.load(in, password.chars)
        finally in.close()
        Right(store)
      } catch {
        case NonFatal(e) =>
          Left(s"$fileSetting: $path cannot be opened with $passwordSetting (${e.getClass.getSimpleName}: " +
            s"${Option(e.getMessage).getOrElse("no detail")})")
      }

  /** The Akka settings of `transport`, to lay over the node's config: for TLS, Artery's `tls-tcp` with the team's
    * stores, mutual authentication and no hostname verification (one team certificate serves every node, and the trust
    * store, not an address, says who belongs to the team); for plain loopback nothing, so the cluster file's `tcp`
    * stays (and a transport an app set itself on loopback is not turned down to it).
    */
  def akkaConfig(transport: Transport): Config = transport match {
    case Transport.PlainLoopback => ConfigFactory.empty()
    case Transport.Tls(s) =>
      val engine = "akka.remote.artery.ssl.config-ssl-engine"
      Map[String, AnyRef](
        "akka.remote.artery.transport" -> "tls-tcp",
        "akka.remote.artery.ssl.ssl-engine-provider" -> "akka.remote.artery.tcp.ConfigSSLEngineProvider",
        s"$engine.key-store" -> s.keyStore.toString,
        s"$engine.key-store-password" -> s.keyStorePassword.reveal,
        s"$engine.key-password" -> s.keyStorePassword.reveal,
        s"$engine.trust-store" -> s.trustStore.toString,
        s"$engine.trust-store-password" -> s.trustStorePassword.reveal,
        s"$engine.protocol" -> s.protocol,
        s"$engine.enabled-algorithms" -> s.algorithms.asJava,
        s"$engine.require-mutual-authentication" -> java.lang.Boolean.TRUE,
        s"$engine.hostname-verification" -> java.lang.Boolean.FALSE
      ).foldLeft(ConfigFactory.empty()) { case (c, (k, v)) => c.withValue(k, ConfigValueFactory.fromAnyRef(v)) }
  }

  /** `c` with the Akka settings of its transport on top; throws `IllegalArgumentException` with the one line of
    * [[decide]] when the node must not start (the launcher prints it and exits 2).
    */
  def secured(c: Config): Config =
    decide(c, storeProblem) match {
      case Right(transport) => akkaConfig(transport).withFallback(c)
      case Left(line)       => throw new IllegalArgumentException(s"cluster: $line")
    }

  /** How the node of `c` talks to the others, in one line for the operator (`robotctl doctor`): Right for a transport
    * it may start with, Left for the refusal.
    */
  def describe(c: Config): Either[String, String] =
    decide(c, storeProblem).map {
      case Transport.PlainLoopback => "plain TCP, every cluster address on loopback: only this machine can join"
      case Transport.Tls(s) =>
        s"${s.protocol} with mutual authentication: only nodes with a certificate of ${s.trustStore} can join"
    }
}
