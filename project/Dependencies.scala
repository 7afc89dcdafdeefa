import sbt._

/** Every version of the build, pinned in one place. */
object Dependencies {
  object V {
    val scala = "2.13.18"
    val akka = "2.6.21"
    // Akka HTTP 10.2.x: the release line built for Akka 2.6, under the Apache License 2.0 (10.4 on is BSL).
    val akkaHttp = "10.2.10"
    // uPlot, the web view's plotting library (MIT), as its npm package republished as a jar (a WebJar).
    val uplot = "1.6.30"
    val selenium = "4.27.0"
    val scalapb: String = _root_.scalapb.compiler.Version.scalapbVersion
    val jeromq = "0.6.0"
    val logback = "1.2.13"
    val jline = "3.29.0"
    val scalatest = "3.2.19"
    val scalacheck = "1.18.1"
    val scalatestPlusScalacheck = "3.2.19.0"
  }

  val scalapbRuntime = "com.thesamet.scalapb" %% "scalapb-runtime" % V.scalapb
  val akkaActorTyped = "com.typesafe.akka" %% "akka-actor-typed" % V.akka
  val akkaStream = "com.typesafe.akka" %% "akka-stream" % V.akka
  val akkaStreamTyped = "com.typesafe.akka" %% "akka-stream-typed" % V.akka
  val akkaSlf4j = "com.typesafe.akka" %% "akka-slf4j" % V.akka
  val akkaClusterTyped = "com.typesafe.akka" %% "akka-cluster-typed" % V.akka
  val jeromq = "org.zeromq" % "jeromq" % V.jeromq
  val logback = "ch.qos.logback" % "logback-classic" % V.logback
  val jline = "org.jline" % "jline" % V.jline
  val akkaHttp = "com.typesafe.akka" %% "akka-http" % V.akkaHttp
  val akkaHttpSprayJson = "com.typesafe.akka" %% "akka-http-spray-json" % V.akkaHttp
  val uplot = "org.webjars.npm" % "uplot" % V.uplot
  // The web view's browser tests drive the system's Chromium through its chromedriver.
  val seleniumChrome = "org.seleniumhq.selenium" % "selenium-chrome-driver" % V.selenium % Test
  val seleniumSupport = "org.seleniumhq.selenium" % "selenium-support" % V.selenium % Test

  val akkaTestkit = "com.typesafe.akka" %% "akka-actor-testkit-typed" % V.akka % Test
  val akkaStreamTestkit = "com.typesafe.akka" %% "akka-stream-testkit" % V.akka % Test
  val scalaReflect = "org.scala-lang" % "scala-reflect" % V.scala % Test
  val scalatest = "org.scalatest" %% "scalatest" % V.scalatest % Test
  val scalacheck = "org.scalacheck" %% "scalacheck" % V.scalacheck % Test
  val scalatestPlusScalacheck = "org.scalatestplus" %% "scalacheck-1-18" % V.scalatestPlusScalacheck % Test

  val testLibs: Seq[ModuleID] = Seq(scalatest, scalacheck, scalatestPlusScalacheck)
  // Tests log through Logback (LogCapturing needs it); the libraries themselves ship no logging backend.
  val akkaTestLibs: Seq[ModuleID] = Seq(akkaTestkit, akkaStreamTestkit, logback % Test)
}
