package robotmiddleware.cluster

import scala.concurrent.{Future, Promise}

import akka.Done
import akka.actor.typed.scaladsl.adapter._
import akka.actor.typed.{ActorSystem, Behavior}
import com.typesafe.config.{Config, ConfigFactory}

/** The gateway with the middleware, and apps in other actor systems or JVMs, as nodes of one Akka Cluster
  * (docs/cluster.md). Once a node has joined, the receptionist is cluster-wide, so `RobotClient.find` and
  * `RobotClient.connect` work on an app node exactly as in one JVM.
  */
object MiddlewareCluster {

  /** The role of the node that runs the gateway and the middleware; the split brain resolver keeps its side. */
  val GatewayRole: String = "gateway"

  /** The role of a node that runs apps. */
  val AppRole: String = "app"

  /** The resource with the cluster settings, kept out of `reference.conf` so one-JVM setups stay local. */
  val ConfigResource: String = "robotmiddleware-cluster.conf"

  /** The config of a node with `role`: `overrides` first, then the application's config (`application`,
    * `application.conf` unless given), then a program's own `defaults`, then the cluster settings of `ConfigResource`,
    * then every module's reference. The role is the node's only cluster role, and picks its port:
    * `robotmiddleware.cluster.gateway-port` or `app-port`. The transport is [[ClusterTls]]'s: TLS with the team's
    * stores, or plain TCP on loopback; a node off loopback without the stores throws `IllegalArgumentException` with
    * one line naming the setting.
    */
  def config(role: String, overrides: Config = ConfigFactory.empty(), defaults: Config = ConfigFactory.empty(),
      application: => Config = ConfigFactory.defaultApplication()): Config =
    ClusterTls.secured(layered(role, overrides, defaults, application))

  /** The layers of [[config]], before [[ClusterTls]] decides the transport. */
  private[cluster] def layered(role: String, overrides: Config, defaults: Config, application: => Config): Config = {
    require(role == GatewayRole || role == AppRole, s"unknown role '$role' ($GatewayRole, $AppRole)")
    val portKey = if (role == GatewayRole) "gateway-port" else "app-port"
    val roles = ConfigFactory.parseString(s"""akka.cluster.roles = ["$role"]""")
    val port = ConfigFactory.parseString(s"akka.remote.artery.canonical.port = $${robotmiddleware.cluster.$portKey}")
    ConfigFactory.load(
      overrides
        .withFallback(roles)
        .withFallback(application)
        .withFallback(defaults)
        .withFallback(port)
        .withFallback(ConfigFactory.parseResources(ConfigResource))
    )
  }

  /** Starts a node with `role` running `guardian`; it joins the seed nodes of its config on its own. */
  def start[T](guardian: Behavior[T], role: String, overrides: Config = ConfigFactory.empty(),
      defaults: Config = ConfigFactory.empty()): ActorSystem[T] =
    start(guardian, config(role, overrides, defaults))

  /** Starts a node running `guardian` with a config made by [[config]]; its transport is checked again, so no config
    * starts a node off loopback without TLS.
    */
  def start[T](guardian: Behavior[T], c: Config): ActorSystem[T] = {
    val secured = ClusterTls.secured(c)
    ActorSystem(guardian, secured.getString("robotmiddleware.cluster.system-name"), secured)
  }

  /** Completes when `system` is an `Up` member of the cluster; never, if it cannot join (bound the wait). */
  def up(system: ActorSystem[_]): Future[Done] = {
    val joined = Promise[Done]()
    akka.cluster.Cluster(system.toClassic).registerOnMemberUp(joined.trySuccess(Done))
    joined.future
  }
}
