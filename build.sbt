import Dependencies._

ThisBuild / scalaVersion := V.scala
ThisBuild / organization := "org.naogateway"
ThisBuild / version := "0.1.0-SNAPSHOT"

// The shared folder beside the checkout holds real packets from real peers (test vectors).
lazy val sharedDir = settingKey[File]("the shared folder beside the checkout (test vectors)")
ThisBuild / sharedDir := (ThisBuild / baseDirectory).value.getAbsoluteFile.getParentFile / "shared"

lazy val strictScalac = Seq(
  scalacOptions ++= Seq(
    "-deprecation",
    "-feature",
    "-unchecked",
    "-encoding",
    "UTF-8",
    "-Xlint",
    "-Ywarn-unused",
    "-Xfatal-warnings",
    "-Wconf:src=src_managed/.*:s"
  ),
  Test / scalacOptions ~= (_.filterNot(_ == "-Xfatal-warnings"))
)

lazy val testSettings = Seq(
  Test / fork := true,
  Test / javaOptions ++= Seq(
    "-Xmx2g",
    s"-Dnaogateway.shared.dir=${(ThisBuild / sharedDir).value.getAbsolutePath}"
  ),
  Test / testOptions += Tests.Argument(TestFrameworks.ScalaTest, "-oDF"),
  Test / parallelExecution := false
)

lazy val proto = (project in file("proto"))
  .settings(
    name := "naogateway-proto",
    Compile / PB.protoSources := Seq(baseDirectory.value / "src" / "main" / "protobuf"),
    Compile / PB.targets := Seq(scalapb.gen() -> (Compile / sourceManaged).value / "scalapb"),
    libraryDependencies ++= Seq(
      scalapbRuntime,
      "com.thesamet.scalapb" %% "scalapb-runtime" % V.scalapb % "protobuf"
    ),
    scalacOptions ++= Seq("-deprecation", "-feature")
  )

lazy val naogateway = (project in file("naogateway"))
  .dependsOn(proto)
  .settings(strictScalac, testSettings)
  .settings(
    name := "naogateway",
    libraryDependencies ++= Seq(akkaActorTyped, akkaStream, akkaStreamTyped, akkaSlf4j, jeromq, logback) ++ testLibs ++ akkaTestLibs
  )

lazy val robotmiddleware = (project in file("robotmiddleware"))
  .dependsOn(naogateway % "compile->compile;test->test")
  .settings(strictScalac, testSettings)
  .settings(
    name := "robotmiddleware",
    libraryDependencies ++= Seq(akkaClusterTyped, scalaReflect) ++ testLibs ++ akkaTestLibs
  )

lazy val apps = (project in file("apps"))
  .dependsOn(robotmiddleware % "compile->compile;test->test")
  .settings(strictScalac, testSettings)
  .settings(
    name := "apps",
    libraryDependencies ++= testLibs ++ akkaTestLibs,
    Compile / mainClass := Some("apps.Launcher"),
    run / fork := true,
    run / connectInput := true,
    run / outputStrategy := Some(StdoutOutput)
  )

lazy val root = (project in file("."))
  .aggregate(proto, naogateway, robotmiddleware, apps)
  .dependsOn(apps % "compile->compile;test->test")
  .settings(strictScalac, testSettings)
  .settings(
    name := "naogateway-root",
    libraryDependencies ++= testLibs ++ akkaTestLibs,
    Compile / mainClass := (apps / Compile / mainClass).value,
    run / fork := true,
    run / connectInput := true,
    run / outputStrategy := Some(StdoutOutput),
    Test / run / fork := true,
    Test / run / javaOptions ++= Seq("-Xmx2g")
  )

// ./sbt "robotctl status": the command-line client of a running gateway's control port.
addCommandAlias("robotctl", "apps/runMain apps.RobotCtl")

// ./sbt bench: the benchmark suite; writes target/bench/results.json and prints a table.
addCommandAlias("bench", "root/Test/runMain bench.BenchSuite")
