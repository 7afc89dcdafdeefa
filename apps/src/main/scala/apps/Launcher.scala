package apps

/** Entry point behind `./sbt run`. */
object Launcher {
  def main(args: Array[String]): Unit =
    println("naogateway launcher")
}
