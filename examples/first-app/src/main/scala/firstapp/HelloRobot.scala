package firstapp

import scala.concurrent.duration._
import scala.concurrent.{Await, ExecutionContext, Future}

import akka.actor.typed.scaladsl.Behaviors
import naogateway.wire.{ActuatorGroup, Posture}
import org.slf4j.LoggerFactory
import robotmiddleware.RobotClient
import robotmiddleware.cluster.MiddlewareCluster

/** A first app: robot 2 of the demo stands up, greets, walks for two seconds and stops; the app then releases the robot
  * and ends. Run it beside the demo (`./sbt run` in the naogateway clone).
  */
object HelloRobot {
  private val log = LoggerFactory.getLogger("firstapp.HelloRobot")

  def main(args: Array[String]): Unit = {
    val system = MiddlewareCluster.start[Nothing](Behaviors.empty, MiddlewareCluster.AppRole)
    implicit val ec: ExecutionContext = system.executionContext
    val cluster = system.settings.config.getConfig("robotmiddleware.cluster")
    val gateway = s"${cluster.getString("gateway-host")}:${cluster.getInt("gateway-port")}"
    val noGateway = new IllegalStateException(s"no gateway at $gateway (ROBOTS_GATEWAY_HOST, ROBOTS_GATEWAY_PORT); " +
      "start the demo first (`./sbt run` in the naogateway clone), then this app again")
    log.info(s"joining the gateway's cluster at $gateway")
    val joined = Future.firstCompletedOf(
      Seq(MiddlewareCluster.up(system), akka.pattern.after(20.seconds)(Future.failed(noGateway))(system)))
    val done = for {
      _ <- joined
      robot <- RobotClient(system, "hello-robot", priority = 1)
      _ = log.info("registered with the middleware as hello-robot; acquiring robot 2")
      _ <- robot.acquire(2, ActuatorGroup.Walk, ActuatorGroup.Speech)
      _ = log.info("robot 2: walk and speech leases held; standing up")
      _ <- robot.posture(2, Posture.Stand)
      _ <- robot.say(2, "Hello, I am robot 2")
      _ <- robot.walk(2, 0.1, 0.0, 0.0)
      _ = log.info("robot 2: walking forward at 0.1 m/s for two seconds")
      _ <- akka.pattern.after(2.seconds)(robot.stop(2))(system)
    } yield {
      robot.release(2, ActuatorGroup.Walk, ActuatorGroup.Speech)
      robot.close()
    }
    done.foreach(_ => println("hello-robot: robot 2 stood up, greeted, walked and stopped"))
    done.failed.foreach(e => println(s"hello-robot failed: ${e.getMessage}"))
    // The app ends when it is done: its node leaves the cluster, then the JVM exits (1 if the app failed). Only main's
    // own thread waits here, outside every actor: nothing above blocks, the steps are futures on the system's threads.
    done.onComplete(_ => system.terminate())
    Await.ready(system.whenTerminated, Duration.Inf)
    if (done.value.exists(_.isFailure)) sys.exit(1)
  }
}
