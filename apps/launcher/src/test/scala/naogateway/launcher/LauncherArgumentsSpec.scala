package naogateway.launcher

import java.nio.file.Files

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.testkit.TempFiles.withTempDir

class LauncherArgumentsSpec extends AnyWordSpec with Matchers {

  "The launcher's command line" must {
    "take a config file, a recording to replay (a file, or a directory's .mcap files by name) and a speed, in any order" in {
      withTempDir("launcher-args") { dir =>
        val b = Files.createFile(dir.resolve("naogateway-20260101-120500-2.mcap"))
        val a = Files.createFile(dir.resolve("naogateway-20260101-120000-1.mcap"))
        Files.createFile(dir.resolve("notes.txt"))
        Launcher.arguments(Nil) shouldBe Launcher.Arguments(None, None)
        Launcher.arguments(Seq("robots.conf")) shouldBe Launcher.Arguments(Some("robots.conf"), None)
        val one = Launcher.arguments(Seq("--replay", a.toString))
        one.replay.map(r => (r.files, r.speed)) shouldBe Some((Vector(a), 1.0))
        val all = Launcher.arguments(Seq("--speed", "4", "robots.conf", "--replay", dir.toString))
        all.configFile shouldBe Some("robots.conf")
        all.replay.map(r => (r.files, r.speed)) shouldBe Some((Vector(a, b), 4.0))
      }
    }

    "refuse a speed without a replay, a missing recording, a speed that is no number, and unknown options" in {
      an[IllegalArgumentException] should be thrownBy Launcher.arguments(Seq("--speed", "2"))
      an[IllegalArgumentException] should be thrownBy Launcher.arguments(Seq("--replay", "/no/such/recording.mcap"))
      an[IllegalArgumentException] should be thrownBy Launcher.arguments(Seq("--replay", "x.mcap", "--speed", "fast"))
      an[IllegalArgumentException] should be thrownBy Launcher.arguments(Seq("--replay"))
      an[IllegalArgumentException] should be thrownBy Launcher.arguments(Seq("--record"))
      an[IllegalArgumentException] should be thrownBy Launcher.arguments(Seq("a.conf", "b.conf"))
    }
  }
}
