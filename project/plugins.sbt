addSbtPlugin("com.thesamet" % "sbt-protoc" % "1.0.8")

libraryDependencies += "com.thesamet.scalapb" %% "compilerplugin" % "0.11.20"
addSbtPlugin("com.github.sbt" % "sbt-native-packager" % "1.11.7")
addSbtPlugin("org.scalameta" % "sbt-scalafmt" % "2.5.2")
// The version from git tags (build.sbt's `version` reads its describe output): what `./sbt publishLocal` publishes.
addSbtPlugin("com.github.sbt" % "sbt-dynver" % "5.1.0")
