// A team's robot app in a repository of its own: it depends on the naogateway libraries that `./sbt publishLocal` in a
// clone of naogateway published (docs/writing-apps.md). Copy this folder, then `./sbt run` here beside the demo.

// The version `./sbt publishLocal` printed in the clone ("published … robotmiddleware_2.13 … <version>").
val naogatewayVersion = "0.1.0-SNAPSHOT"

ThisBuild / scalaVersion := "2.13.18"

lazy val root = (project in file("."))
  .settings(
    name := "first-app",
    libraryDependencies ++= Seq(
      // RobotInterface and RobotClient, with the api's types (snapshots, vision frames, failures) and the cluster.
      "org.naogateway" %% "robotmiddleware" % naogatewayVersion,
      // Logging: Akka's lines through SLF4J (application.conf) into Logback (logback.xml).
      "com.typesafe.akka" %% "akka-slf4j" % "2.6.21",
      "ch.qos.logback" % "logback-classic" % "1.2.13"
    ),
    // The app runs in a JVM of its own, which sbt waits for: it ends when the app is done.
    run / fork := true,
    run / outputStrategy := Some(StdoutOutput),
    Compile / mainClass := Some("firstapp.HelloRobot")
  )
