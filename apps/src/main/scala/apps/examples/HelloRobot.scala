package apps.examples

import scala.concurrent.duration._

import akka.actor.typed.ActorSystem
import akka.actor.typed.scaladsl.Behaviors
import naogateway.wire.{ActuatorGroup, Posture}
import robotmiddleware.cluster.MiddlewareCluster
import robotmiddleware.RobotClient

/** A first app: stand robot 2 up, greet, walk for two seconds, stop. Run it next to `./sbt run`. */
object HelloRobot {
  def main(args: Array[String]): Unit = {
    val system = MiddlewareCluster.start[Nothing](Behaviors.empty, MiddlewareCluster.AppRole)
    implicit val ec: scala.concurrent.ExecutionContext = system.executionContext
    val done = for {
      robot <- RobotClient(system, "hello-robot", priority = 1)
      _ <- robot.acquire(2, ActuatorGroup.Walk, ActuatorGroup.Speech)
      _ <- robot.posture(2, Posture.Stand)
      _ <- robot.say(2, "Hello, I am robot 2")
      _ <- robot.walk(2, 0.1, 0.0, 0.0)
      _ <- akka.pattern.after(2.seconds)(robot.stop(2))(system)
    } yield robot.close()
    done.foreach(_ => println("hello-robot: robot 2 stood up, greeted, walked and stopped"))
    done.failed.foreach(e => println(s"hello-robot failed: ${e.getMessage}"))
    done.onComplete(_ => system.terminate())
    val _: ActorSystem[Nothing] = system
  }
}
