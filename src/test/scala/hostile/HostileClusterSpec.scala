package hostile

import java.io.IOException
import java.net.SocketTimeoutException
import java.nio.charset.StandardCharsets
import java.nio.file.{Files, Path}
import java.security.KeyStore
import java.security.cert.X509Certificate
import javax.net.ssl.{KeyManagerFactory, SSLContext, SSLSocket, TrustManager, X509TrustManager}

import scala.concurrent.duration._

import akka.actor.testkit.typed.scaladsl.{ActorTestKit, LogCapturing}
import akka.actor.typed.ActorRef
import akka.actor.typed.scaladsl.Behaviors
import akka.cluster.MemberStatus
import akka.cluster.typed.{Cluster, Join}
import com.typesafe.config.{Config, ConfigFactory}
import org.scalatest.BeforeAndAfterAll
import org.scalatest.concurrent.ScalaFutures
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.api.GatewayEvent
import naogateway.access.RobotAccess
import naogateway.testkit.TempFiles
import robotmiddleware.cluster.MiddlewareClusterSpec.{appOverrides, fakeGateway, fakeRobot, gatewayOverrides}
import robotmiddleware.cluster.{MiddlewareCluster, TeamKeys}
import robotmiddleware.{MiddlewareSettings, RobotClient, RobotMiddleware}

/** The cluster port as a stranger on the team's network finds it: a gateway node running Artery over TLS with the
  * team's files (made by keytool as docs/cluster.md shows), on loopback. An app with the team's files joins and talks
  * to the middleware; a node with a key of its own (under the team's name, trusting the team's captured certificate)
  * and a node speaking plain TCP never become members, never find the middleware, never deliver a message, and the
  * gateway stays Up; a hand-made TLS client gets no session without the team's certificate.
  */
class HostileClusterSpec
    extends AnyWordSpec
    with Matchers
    with ScalaFutures
    with BeforeAndAfterAll
    with LogCapturing {

  implicit override val patienceConfig: PatienceConfig = PatienceConfig(30.seconds, 50.millis)

  /** How long a stranger gets to join, find the middleware or deliver a message: longer than a join takes on loopback
    * (the team's app is Up within a few seconds) and than the seed retry interval (5 s), so it tried again.
    */
  private val StrangerWait = 8.seconds

  private lazy val dir: Path = Files.createTempDirectory("hostile-cluster")
  private lazy val tool: Path = TeamKeys.keytool.getOrElse(cancel("the JDK's keytool is not beside this JVM"))
  private lazy val team = TeamKeys.team(tool, dir, "team-store-4242", "team-trust-4242")
  private lazy val stranger =
    TeamKeys.stranger(tool, Files.createDirectories(dir.resolve("stranger")), team.certificate, "stranger-4242")

  private var nodes = List.empty[ActorTestKit]

  private def node(role: String, config: Config): ActorTestKit = {
    val n = ActorTestKit(MiddlewareCluster.start(Behaviors.empty, role, config))
    nodes ::= n
    n
  }

  // The gateway node: TLS with the team's files, on 127.0.0.1, a free port; it joins itself.
  private lazy val gatewayNode = {
    val n = node(MiddlewareCluster.GatewayRole, team.stores.config.withFallback(gatewayOverrides))
    val c = Cluster(n.system)
    c.manager ! Join(c.selfMember.address)
    n
  }
  private def gatewayCluster = Cluster(gatewayNode.system)
  private lazy val gatewayPort = gatewayCluster.selfMember.address.port.get

  // The middleware in front of a fake gateway with robot 7, as in MiddlewareClusterSpec.
  private lazy val middleware = {
    val response = gatewayNode.createTestProbe[RobotAccess.Call]()
    val vision = gatewayNode.createTestProbe[RobotAccess.RegisterVision]()
    val subscriptions = gatewayNode.createTestProbe[ActorRef[GatewayEvent]]()
    val robot = gatewayNode.spawn(fakeRobot(RobotAccess.Opened(7, response.ref, vision.ref)), "robot-7")
    val gateway = gatewayNode.spawn(fakeGateway(robot, subscriptions.ref), "gateway")
    gatewayNode.spawn(RobotMiddleware(gateway, MiddlewareSettings(gatewayNode.system)), "middleware")
  }

  // Where any node may send a plain string (the primitive serializer): what arrives, came through.
  private lazy val inbox = gatewayNode.createTestProbe[String]("inbox")

  private def sendToInbox(from: ActorTestKit, text: String): Unit =
    from.system.classicSystem.actorSelection(inbox.ref.path.toStringWithAddress(gatewayCluster.selfMember.address)) !
      text

  /** What the gateway's cluster port does with a TLS connection that presents `keys`' certificate (none without), the
    * way a hand-made client would try it: it trusts whatever the gateway presents, completes its side of the handshake
    * and sends Artery's magic bytes. "refused" when the session ends in an alert or a close; "open" when it still
    * stands after `open` (the server waits for the rest of Artery's header).
    */
  private def rawTls(keys: Option[TeamKeys.Stores], open: FiniteDuration = 2.seconds): String = {
    val keyManagers = keys.map { s =>
      val store = KeyStore.getInstance(KeyStore.getDefaultType)
      val in = Files.newInputStream(s.keyStore)
      try store.load(in, s.keyStorePassword.toCharArray)
      finally in.close()
      val factory = KeyManagerFactory.getInstance(KeyManagerFactory.getDefaultAlgorithm)
      factory.init(store, s.keyStorePassword.toCharArray)
      factory.getKeyManagers
    }
    val trustAnything: TrustManager = new X509TrustManager {
      def checkClientTrusted(chain: Array[X509Certificate], authType: String): Unit = ()
      def checkServerTrusted(chain: Array[X509Certificate], authType: String): Unit = ()
      def getAcceptedIssuers: Array[X509Certificate] = Array.empty
    }
    val context = SSLContext.getInstance("TLSv1.3")
    context.init(keyManagers.orNull, Array(trustAnything), null)
    val socket = context.getSocketFactory.createSocket("127.0.0.1", gatewayPort).asInstanceOf[SSLSocket]
    try {
      // The refusal comes as an alert after the client's side of a TLS 1.3 handshake: a long wait for it, a short
      // one for a session that stays open.
      socket.setSoTimeout(15000)
      socket.startHandshake()
      socket.getOutputStream.write("AKKA".getBytes(StandardCharsets.US_ASCII))
      socket.getOutputStream.flush()
      if (keys.contains(team.stores)) socket.setSoTimeout(open.toMillis.toInt)
      if (socket.getInputStream.read() < 0) "refused" else "answered"
    } catch {
      case _: SocketTimeoutException => "open"
      case _: IOException            => "refused" // SSLException is one
    } finally socket.close()
  }

  override protected def afterAll(): Unit = {
    nodes.foreach(_.shutdownTestKit())
    TempFiles.deleteRecursively(dir)
    super.afterAll()
  }

  "The gateway node, on TLS with the team's files (on loopback here, as off it)" should {
    "let an app with the team's certificate join, find the middleware and reach it" in {
      middleware
      gatewayNode.system.settings.config.getString("akka.remote.artery.transport") shouldBe "tls-tcp"
      MiddlewareCluster.up(gatewayNode.system).futureValue
      val app = node(MiddlewareCluster.AppRole, team.stores.config.withFallback(appOverrides(gatewayPort)))
      MiddlewareCluster.up(app.system).futureValue
      val robot = RobotClient(app.system, "team-app", priority = 1).futureValue
      robot.robots().futureValue.map(_.robotId) shouldBe Vector(7)
      sendToInbox(app, "from the team")
      inbox.expectMessage(10.seconds, "from the team")
      robot.close()
    }

    "refuse a node with a certificate of its own and a node without TLS: no membership, no middleware, no message" in {
      val strangers = Map(
        "a stranger's certificate under the team's name" ->
          node(MiddlewareCluster.AppRole, stranger.config.withFallback(appOverrides(gatewayPort))),
        "plain TCP, no certificate" -> node(MiddlewareCluster.AppRole, appOverrides(gatewayPort))
      )
      strangers("plain TCP, no certificate").system.settings.config.getString("akka.remote.artery.transport") shouldBe
        "tcp"
      val joined = strangers.map { case (who, n) => who -> MiddlewareCluster.up(n.system) }
      val found = strangers.map { case (who, n) => who -> RobotClient.find(n.system, StrangerWait) }
      strangers.foreach { case (who, n) => sendToInbox(n, s"from $who") }
      // Each find gives up after the wait: in all that time no stranger saw the middleware in the receptionist.
      found.foreach { case (who, f) => withClue(who)(f.failed.futureValue shouldBe a[NoSuchElementException]) }
      inbox.expectNoMessage(100.millis)
      joined.foreach { case (who, up) => withClue(who)(up.isCompleted shouldBe false) }
      val members = gatewayCluster.state.members.map(_.address)
      strangers.foreach { case (who, n) =>
        withClue(who)(members should not contain Cluster(n.system).selfMember.address)
      }
      gatewayCluster.selfMember.status shouldBe MemberStatus.Up
      gatewayCluster.state.members.count(_.status == MemberStatus.Up) shouldBe 2 // the gateway and the team's app
    }

    "end a hand-made TLS session that presents a stranger's certificate or none, and keep the team's open" in {
      // Akka's own handshake would fail anyway on the gateway's connection back to the stranger; a hand-made client
      // needs none, so only the gateway's demand for the team's certificate stops it.
      rawTls(Some(stranger)) shouldBe "refused"
      rawTls(None) shouldBe "refused"
      rawTls(Some(team.stores)) shouldBe "open"
      gatewayCluster.selfMember.status shouldBe MemberStatus.Up
    }
  }
}
