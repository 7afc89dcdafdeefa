package apps

import com.typesafe.config.ConfigFactory
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import apps.datagram.DatagramDoorSettings
import apps.zeromq.ZeroMqSettings

/** The doors' rules as pure functions: when a door is on, and which bind addresses a door without a token refuses. */
class DoorsSpec extends AnyWordSpec with Matchers {

  private def config(text: String) = ConfigFactory.parseString(text).withFallback(ConfigFactory.load()).resolve()

  "A door's switch" should {
    "read on, off and auto (HOCON's truth values included) and name the key of anything else" in {
      DoorSwitch.parse("on") shouldBe Right(DoorSwitch.On)
      DoorSwitch.parse("true") shouldBe Right(DoorSwitch.On)
      DoorSwitch.parse(" OFF ") shouldBe Right(DoorSwitch.Off)
      DoorSwitch.parse("no") shouldBe Right(DoorSwitch.Off)
      DoorSwitch.parse("auto") shouldBe Right(DoorSwitch.Auto)
      val e = the[IllegalArgumentException] thrownBy
        DoorSwitch.read(ConfigFactory.parseString("enabled = maybe"), "enabled", "apps.web")
      e.getMessage should include("apps.web.enabled")
      e.getMessage should include("maybe")
    }

    "open by name whatever the robots, and auto only without real robots" in {
      for (real <- Seq(true, false)) {
        Doors.open(DoorSwitch.On, real) shouldBe true
        Doors.open(DoorSwitch.Off, real) shouldBe false
      }
      Doors.open(DoorSwitch.Auto, realRobots = false) shouldBe true
      Doors.open(DoorSwitch.Auto, realRobots = true) shouldBe false
    }

    "be auto in every door's reference" in {
      val c = ConfigFactory.load()
      DatagramDoorSettings.fromConfig(c.getConfig(DatagramDoorSettings.ConfigPath)).enabled shouldBe DoorSwitch.Auto
      ZeroMqSettings.fromConfig(c.getConfig(ZeroMqSettings.ConfigPath), "x").enabled shouldBe DoorSwitch.Auto
      apps.web.WebSettings.fromConfig(c.getConfig(apps.web.WebSettings.ConfigPath)).enabled shouldBe DoorSwitch.Auto
    }
  }

  "Real robots" should {
    "be configured with no simulated robots, with any robot listed, or without the launcher's block" in {
      Doors.realRobots(config("apps.launcher.simulated-robots = 3")) shouldBe false
      Doors.realRobots(config("apps.launcher.simulated-robots = 0")) shouldBe true
      Doors.realRobots(config(
          "apps.launcher.simulated-robots = 3\nnaogateway.robots = [ { id = 1, address = \"10.0.0.1\" } ]")) shouldBe true
      Doors.realRobots(ConfigFactory.parseString("naogateway.robots = []")) shouldBe true
    }
  }

  "The doors without a token" should {
    "tell loopback from other addresses without a name that does not resolve passing" in {
      Seq("127.0.0.1", "127.0.0.42", "::1", "[::1]", "localhost").foreach(h =>
        (h, Doors.loopback(h)) shouldBe ((h, true)))
      Seq("0.0.0.0", "*", "", "192.168.1.5", "::", "no-such-host.invalid").foreach(h =>
        (h, Doors.loopback(h)) shouldBe ((h, false)))
    }

    "find the host of a ZeroMQ tcp endpoint, and none for ipc or inproc" in {
      Doors.zeroMqHost("tcp://127.0.0.1:5555") shouldBe Some("127.0.0.1")
      Doors.zeroMqHost("tcp://*:5555") shouldBe Some("*")
      Doors.zeroMqHost("tcp://[::1]:5555") shouldBe Some("[::1]")
      Doors.zeroMqHost("ipc:///tmp/naogateway") shouldBe None
      Doors.zeroMqHost("inproc://x") shouldBe None
    }

    "refuse the datagram door off loopback" in {
      val c = ConfigFactory.load().getConfig(DatagramDoorSettings.ConfigPath)
      val door = DatagramDoorSettings.fromConfig(c)
      door.refusal shouldBe None
      door.copy(bindAddress = "127.0.0.9").refusal shouldBe None
      val refused = door.copy(bindAddress = "0.0.0.0").refusal
      refused.get should include("apps.datagram-door.bind-address 0.0.0.0 is not loopback")
      door.copy(bindAddress = "192.168.1.10").refusal should not be empty
    }

    "refuse the ZeroMQ endpoint when either socket is off loopback" in {
      val z = ZeroMqSettings.fromConfig(ConfigFactory.load().getConfig(ZeroMqSettings.ConfigPath), "x")
      z.refusal shouldBe None
      z.copy(bind = "ipc:///tmp/requests").refusal shouldBe None
      z.copy(bind = "tcp://*:5555").refusal.get should include("apps.zeromq.bind tcp://*:5555 is not loopback")
      z.copy(publish = "tcp://0.0.0.0:5556").refusal.get should include("apps.zeromq.publish")
    }
  }
}
