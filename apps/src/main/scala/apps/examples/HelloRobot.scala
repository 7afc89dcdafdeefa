package apps.examples

import scala.concurrent.duration._

import akka.actor.typed.ActorSystem
import akka.actor.typed.scaladsl.Behaviors
import naogateway.wire.{ActuatorGroup, Posture}
import robotmiddleware.cluster.MiddlewareCluster
import robotmiddleware.RobotClient

/** A first app: stand robot 1 up, greet, walk for two seconds, stop. Run it next to `./sbt run`. */
object HelloRobot {
  def main(args: Array[String]): Unit = {
    val system = MiddlewareCluster.start[Nothing](Behaviors.empty, MiddlewareCluster.AppRole)
    implicit val ec: scala.concurrent.ExecutionContext = system.executionContext
    val done = for {
      robot <- RobotClient(system, "hello-robot", priority = 1)
      _ <- robot.acquire(1, ActuatorGroup.Walk, ActuatorGroup.Speech)
      _ <- robot.posture(1, Posture.Stand)
      _ <- robot.say(1, "Hello, I am robot 1")
      _ <- robot.walk(1, 0.1, 0.0, 0.0)
      _ <- akka.pattern.after(2.seconds)(robot.stop(1))(system)
    } yield robot.close()
    done.failed.foreach(e => println(s"hello-robot failed: ${e.getMessage}"))
    done.onComplete(_ => system.terminate())
    val _: ActorSystem[Nothing] = system
  }
}
