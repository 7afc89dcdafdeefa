import Dependencies._

ThisBuild / scalaVersion := V.scala
ThisBuild / organization := "org.naogateway"
// The version from git tags (sbt-dynver): a clean checkout at tag v1.2.0 is 1.2.0; any other commit, or uncommitted
// changes, is the next patch as a snapshot (1.2.1-SNAPSHOT), so a team's build names one version until the next release;
// with no tag yet, 0.1.0-SNAPSHOT. `./sbt publishLocal` publishes the libraries an app needs under it (docs/writing-apps.md).
ThisBuild / version := Publishing.version(dynverGitDescribeOutput.value)
ThisBuild / versionScheme := Some("early-semver")

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
  Test / scalacOptions ~= (_.filterNot(_ == "-Xfatal-warnings")),
  // The package carries no API docs; scaladoc's own lint must not break `./sbt dist`.
  Compile / doc / scalacOptions ~= (_.filterNot(_ == "-Xfatal-warnings")),
  Compile / packageDoc / publishArtifact := false
)

// Each module's specs run one after another in a JVM of its own (Test / fork, parallelExecution off). sbt's own
// default lets one such JVM run at a time in the whole build; most specs wait on sockets, timers and other processes
// rather than compute (the integration specs' JVM used about 0.2 of a core), so two modules' JVMs run side by side, and
// the task limit is raised by two so that compiling the next modules goes on beside them. Shared resources across the
// JVMs: loopback addresses (naogateway.testkit.TestLoopback), the Python venv (apps.zeromq.PythonEnv, file-locked).
Global / concurrentRestrictions := Seq(
  Tags.limitAll(java.lang.Runtime.getRuntime.availableProcessors + 2),
  Tags.limit(Tags.ForkedTestGroup, 2),
  Tags.exclusiveGroup(Tags.Clean)
)

lazy val testSettings = Seq(
  Test / fork := true,
  Test / javaOptions ++= Seq("-Xmx2g"),
  Test / testOptions += Tests.Argument(TestFrameworks.ScalaTest, "-oDF"),
  Test / parallelExecution := false
)

// The forked run's stdout is a pipe to sbt, so the launcher cannot see a terminal itself: sbt tells it
// whether its own console is one (apps.StatusPrinter reads this).
lazy val terminalEnv = run / envVars += "NAOGATEWAY_TERMINAL" -> (System.console() != null).toString

// What `./sbt publishLocal` leaves out: an app needs proto, wire, api, access and robotmiddleware (the libraries behind
// `robotmiddleware.RobotInterface`); the gateway, the simulator, the doors and the launcher run in the demo or the
// package, never inside a team's app.
lazy val notPublished = publish / skip := true

// The team's first app (docs/writing-apps.md): a project of its own in examples/first-app, which a team copies and
// builds against the published libraries. Its source is compiled here too, with the strict flags, so the docs' first
// app always compiles against the code; `./sbt "apps/runMain firstapp.HelloRobot"` runs it with its own logging.
lazy val firstApp = "examples/first-app"

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

// The robots' wire format (frames, messages, RPC, HaViMo, the secure stream, GameController packets): pure
// code over the protobuf classes. No Akka on its classpath, so none can creep in (wire.NoAkkaSpec checks).
lazy val wire = (project in file("naogateway/wire"))
  .dependsOn(proto)
  .settings(strictScalac, testSettings)
  .settings(
    name := "naogateway-wire",
    libraryDependencies ++= testLibs
  )

// What apps may see of the gateway: snapshots, events, failures, vision frames, link, traffic and gateway figures, the
// recording's figures (naogateway.api, naogateway.api.recording); plain data over the wire types (postures, groups,
// values). No Akka on its classpath (naogateway.api.ApiLayerSpec checks; ApiBoundarySpec shows scalac refusing a
// probe that imports naogateway.gateway.Gateway), so no actor internal can creep in.
lazy val api = (project in file("naogateway/api"))
  .dependsOn(wire)
  .settings(strictScalac, testSettings)
  .settings(
    name := "naogateway-api",
    // scala-compiler in tests: ApiBoundarySpec compiles probe sources against the api's classpath.
    libraryDependencies ++= testLibs :+ ("org.scala-lang" % "scala-compiler" % V.scala % Test)
  )

// The gateway's public actor protocol: what the middleware may send the gateway and its robots (GatewayAccess,
// RobotAccess), and the restart back-off it reads from its settings; on the api and akka-actor-typed only. The
// middleware depends on this, not on the gateway; the gateway implements it, wrapping each message into its actors'
// private commands as it arrives (no extra actor). MiddlewareLayerSpec shows scalac refusing a gateway internal there.
lazy val access = (project in file("naogateway/access"))
  .dependsOn(api)
  .settings(strictScalac, testSettings)
  .settings(
    name := "naogateway-access",
    libraryDependencies ++= Seq(akkaActorTyped) ++ testLibs
  )

// The two socket loops (naogateway.transport): the ZeroMQ loop (one thread owning its sockets, woken through a pipe) and
// the datagram port with the loop that reads it (one thread that runs an Akka dispatcher's tasks and waits in the
// selector of the ports attached to it), with the rate-limited log they share. The gateway's robot links and the apps'
// ZeroMQ endpoint and datagram door all run on them, so they are a module of their own that apps may see without the
// gateway. No api, no wire: sockets and threads only.
lazy val transport = (project in file("naogateway/transport"))
  .settings(strictScalac, testSettings)
  .settings(
    name := "naogateway-transport",
    notPublished,
    libraryDependencies ++= Seq(akkaActorTyped, akkaSlf4j, jeromq) ++ testLibs
  )

// The test kit (naogateway.testkit): fixtures the specs of several modules share (free loopback ports, settings
// tables, captured relays, GameController packets) and the tests' logging (logback-test.xml). Its
// code is test code, used only at test scope (`testkit % Test`) and never published; it sees the wire format only,
// so every module's tests may use it, the gateway's and the simulator's too.
lazy val testkit = (project in file("naogateway/testkit"))
  .dependsOn(wire)
  .settings(strictScalac, testSettings)
  .settings(
    name := "naogateway-testkit",
    notPublished,
    // Its code is test code: the test libraries at compile scope (akka-actor brings the config library).
    libraryDependencies ++= Seq(logback, akkaActorTyped, "org.scalatest" %% "scalatest" % V.scalatest)
  )

// The gateway (naogateway.gateway): the robots' actors in .robot, the GameController's watch and gate in
// .gamecontroller, the robot links in .link, the recorder in .recording.
lazy val naogateway = (project in file("naogateway"))
  .dependsOn(proto, wire, api, access, transport, testkit % Test)
  .settings(strictScalac, testSettings)
  .settings(
    name := "naogateway",
    notPublished,
    libraryDependencies ++= Seq(akkaActorTyped, akkaStream, akkaStreamTyped, akkaSlf4j,
      jeromq) ++ testLibs ++ akkaTestLibs
  )

// The simulator: simulated robots and their firmware, the GS1500M model, the lossy network, the fleet and the
// simulated GameController. The demo runs it, so it is a jar of its own beside the gateway's, not inside it.
// Its tests are the simulator's own; they take wire's GameController vectors and stream test kit through test->test.
lazy val sim = (project in file("naogateway/sim"))
  .dependsOn(naogateway, wire % "compile->compile;test->test", testkit % Test)
  .settings(strictScalac, testSettings)
  .settings(
    name := "naogateway-sim",
    notPublished,
    libraryDependencies ++= testLibs ++ akkaTestLibs
  )

// The gateway's integration specs: the gateway driven end to end by simulated robots over loopback (sbt allows no
// cycle from naogateway's tests into sim). Test sources only, nothing to publish; its two fixtures that start a gateway
// (GatewayFixture, GatewayInternals) serve the middleware's and the apps' specs and the bench too, through test->test:
// they need the gateway and the simulator, which the test kit below them cannot see.
lazy val integration = (project in file("naogateway/integration"))
  .dependsOn(naogateway, sim % "compile->compile;test->test", wire % "compile->compile;test->test", testkit % Test)
  .settings(strictScalac, testSettings)
  .settings(
    name := "naogateway-integration",
    notPublished,
    libraryDependencies ++= testLibs ++ akkaTestLibs
  )

// The middleware: it sees the api and the gateway's access protocol, never the gateway itself (only its specs drive a
// real gateway, at test scope). MiddlewareLayerSpec compiles a probe that names a gateway internal against the main
// classpath and expects scalac to refuse it.
lazy val robotmiddleware = (project in file("robotmiddleware"))
  .dependsOn(api, access, naogateway % Test, wire % "test->test", sim % Test, integration % "test->test",
    testkit % Test)
  .settings(strictScalac, testSettings)
  .settings(
    name := "robotmiddleware",
    // The cluster's own messages (cluster.proto) import the robot protos of `proto`, whose classes that module
    // already holds. protoc sees only the imported files, not `proto`'s package.proto with its flat_package
    // option, so the generator is told flat packages itself (both packages use them).
    Compile / PB.targets := Seq(scalapb.gen(flatPackage = true) -> (Compile / sourceManaged).value / "scalapb"),
    Compile / PB.includePaths ++= (proto / Compile / PB.protoSources).value,
    libraryDependencies ++= Seq(akkaClusterTyped, akkaStream, akkaStreamTyped, scalaReflect) ++ testLibs ++
      akkaTestLibs,
    libraryDependencies += "com.thesamet.scalapb" %% "scalapb-runtime" % V.scalapb % "protobuf",
    // scala-compiler in tests: MiddlewareLayerSpec compiles probe sources against the main classpath.
    libraryDependencies += "org.scala-lang" % "scala-compiler" % V.scala % Test,
    // The main classpath, as a file the layer spec reads (the test JVM's own classpath holds the gateway).
    Test / resourceGenerators += Def.task {
      val out = (Test / resourceManaged).value / "robotmiddleware-main-classpath.txt"
      IO.write(out, (Compile / fullClasspath).value.map(_.data.getAbsolutePath).mkString("\n"))
      Seq(out)
    }.taskValue
  )

// The apps: the status and web views, the control port, the ZeroMQ endpoint, the ball follower, teleop. They see the
// middleware and the api; the launcher hands them what they read of the gateway.
lazy val apps = (project in file("apps"))
  .dependsOn(api, transport, robotmiddleware % "compile->compile;test->test", sim % "test->test",
    integration % "test->test", testkit % Test)
  .settings(strictScalac, testSettings)
  .settings(
    name := "apps",
    notPublished,
    Compile / unmanagedSourceDirectories += (ThisBuild / baseDirectory).value / firstApp / "src" / "main" / "scala",
    // `./sbt "apps/runMain …"` runs the app in a JVM of its own that lives until the app ends, with the first app's
    // logging (Logback; Akka's own lines through SLF4J): its logback.xml and application.conf.
    libraryDependencies += logback % Runtime,
    run / fork := true,
    run / connectInput := true,
    run / outputStrategy := Some(StdoutOutput),
    run / javaOptions ++= {
      val resources = (ThisBuild / baseDirectory).value / firstApp / "src" / "main" / "resources"
      Seq(s"-Dlogback.configurationFile=${resources / "logback.xml"}",
        s"-Dconfig.file=${resources / "application.conf"}")
    },
    terminalEnv,
    // The boundary the compiler keeps: apps' main code compiles without the gateway's and the simulator's classes, so
    /* an app that imports a gateway internal (naogateway.gateway.Gateway, an actor, the settings) does not build. What
     * apps */
    // may see is the api, the wire format, the middleware (with the access protocol it speaks) and the socket loops of
    // the transport;
    // the launcher hands them the rest. Since the middleware no longer brings the gateway, this drop is a second guard.
    Compile / dependencyClasspath := {
      val internals = Set((naogateway / Compile / classDirectory).value, (sim / Compile / classDirectory).value)
      (Compile / dependencyClasspath).value.filterNot(entry => internals(entry.data))
    },
    libraryDependencies ++= Seq(jline, akkaHttp, akkaHttpSprayJson, uplot, seleniumChrome, seleniumSupport) ++
      testLibs ++ akkaTestLibs,
    // scala-compiler in tests: ModuleLayersSpec compiles the apps that see only the api without the gateway's classes.
    libraryDependencies += "org.scala-lang" % "scala-compiler" % V.scala % Test
  )

// The launcher: the one module that sees everything (gateway, simulator, middleware, apps). It wires the demo node
// (Launcher), checks the machine before it starts (Preflight) and while it runs (Doctor), hands the apps the gateway's
// read-only view, and is the package (./sbt dist): bin/naogateway, bin/robotctl (whose offline doctor reads the
// launcher's config) and bin/teleop, with the Python client.
lazy val launcher = (project in file("apps/launcher"))
  .dependsOn(apps % "compile->compile;test->test", sim, testkit % Test)
  .enablePlugins(JavaAppPackaging)
  .settings(strictScalac, testSettings)
  .settings(
    name := "naogateway-launcher",
    notPublished,
    // The launcher is the one module with a logging backend at compile scope (its logback.xml); the libraries log
    // through SLF4J only.
    libraryDependencies ++= Seq(logback) ++ testLibs ++ akkaTestLibs,
    Compile / mainClass := Some("naogateway.launcher.Launcher"),
    // The package (./sbt dist): bin/naogateway for the launcher, and one script for each of these entry points.
    Compile / discoveredMainClasses := Seq("naogateway.launcher.RobotCtl", "apps.Teleop"),
    executableScriptName := "naogateway",
    Universal / packageName := s"naogateway-${version.value}",
    Universal / mappings := (Universal / mappings).value.map {
      case (file, "bin/robot-ctl")     => file -> "bin/robotctl"
      case (file, "bin/robot-ctl.bat") => file -> "bin/robotctl.bat"
      case other                       => other
    },
    // The Python client (apps/python, installable with pip) with the .proto files it generates its classes from: in
    // the repository naogateway_client/proto links to proto/src/main/protobuf, in the package it is a copy.
    Universal / mappings ++= {
      val python = (apps / baseDirectory).value / "python"
      val sources = (python ** ("*.py" || "*.toml" || "*.md" || "*.txt" || "py.typed")).get
        .filterNot(f =>
          Seq("build", "proto", "__pycache__").exists(d => f.getPath.contains(s"/$d/")) || f.getPath.contains(
            ".egg-info"))
      val protos = (proto / Compile / PB.protoSources).value.head
      sources.map(f => f -> s"python/${IO.relativize(python, f).get}") ++
        (protos ** "*.proto").get.map(f => f -> s"python/naogateway_client/proto/${IO.relativize(protos, f).get}")
    },
    // Logs beside the installation, not in the directory the operator happens to start from.
    bashScriptExtraDefines += """addJava "-Dnaogateway.log.dir=${app_home}/../logs"""",
    // Recordings likewise, unless the operator names a directory.
    bashScriptExtraDefines += """[ -n "$NAOGATEWAY_RECORDING_DIR" ] || export NAOGATEWAY_RECORDING_DIR="${app_home}/../recordings"""",
    // Every JVM of the package compiles with the quick tier only (C1): robotctl because it is short-lived, the
    // gateway and teleop because a field's load (a few robots' keep-alives and camera frames) is far below what C1's
    // code handles, while with the optimising tier the code that runs a few times a second sits for minutes in C1's
    // slower profiling tier and the compiler keeps working (docs/benchmarks.md, "Where the idle demo's CPU goes").
    // robotctl also starts faster with the serial collector. The gateway and teleop compile a method after a tenth of
    // the JVM's default count of calls, since code that runs a few times a second (the game, the cluster's rounds, a
    // view's question) would otherwise run interpreted for minutes, and C1 inlines methods up to 70 bytecodes (35 by
    // default), which covers Scala's small forwarders and adapters. The JVM's sampler of its performance counters
    // (what jstat reads) runs every second rather than every 50 ms: 20 wake-ups a second for figures nobody reads.
    bashScriptExtraDefines += """addJava "-XX:TieredStopAtLevel=1"""",
    bashScriptExtraDefines += """case " $* " in *" -main naogateway.launcher.RobotCtl "*) addJava "-XX:+UseSerialGC";; *) addJava "-XX:CompileThresholdScaling=0.1"; addJava "-XX:C1MaxInlineSize=70"; addJava "-XX:PerfDataSamplingInterval=1000";; esac""",
    terminalEnv,
    run / fork := true,
    run / connectInput := true,
    run / outputStrategy := Some(StdoutOutput)
  )

lazy val root = (project in file("."))
  .aggregate(proto, wire, api, access, transport, testkit, naogateway, sim, integration, robotmiddleware, apps,
    launcher)
  .dependsOn(launcher % "compile->compile;test->test")
  .settings(strictScalac, testSettings)
  .settings(
    name := "naogateway-root",
    notPublished,
    // The bench's web figures (bench.WebBench) drive the web view with these, as the apps tests do.
    libraryDependencies ++= Seq(akkaHttp, akkaHttpSprayJson, seleniumChrome,
      seleniumSupport) ++ testLibs ++ akkaTestLibs,
    Compile / mainClass := (launcher / Compile / mainClass).value,
    terminalEnv,
    run / fork := true,
    run / connectInput := true,
    run / outputStrategy := Some(StdoutOutput),
    Test / run / fork := true,
    Test / run / javaOptions ++= Seq("-Xmx2g"),
    // A clone's first app takes minutes (two sbt builds from scratch): ./sbt firstApp runs it, ./sbt test does not.
    Test / testOptions += Tests.Filter(_ != "endtoend.FirstAppSpec")
  )

// ./sbt dist: the installable package, one .tgz archive; its path is printed.
dist / aggregate := false
dist := {
  val archive = (launcher / Universal / packageZipTarball).value
  println(s"package: ${archive.getAbsolutePath}")
  archive
}

// ./sbt "robotctl status": the command-line client of a running gateway's control port.
addCommandAlias("robotctl", "launcher/runMain naogateway.launcher.RobotCtl")

// ./sbt firstApp: a newcomer's path in a clone of HEAD (endtoend.FirstAppSpec): publishLocal, the template copied to a
// folder of its own, its app run against the demo; it must walk robot 2. Minutes long, so CI runs it apart (.ci/run).
addCommandAlias("firstApp", "root/Test/runMain endtoend.FirstAppCheck")

// ./sbt bench: the benchmark suite; writes target/bench/results.json and prints a table. It stages the package
// first, because the soak (./sbt "bench soak [minutes]") runs the packaged gateway.
addCommandAlias("bench", "launcher/stage; root/Test/runMain bench.BenchSuite")
