package naogateway.launcher

import java.nio.file.Files

import com.typesafe.config.ConfigFactory
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

class RobotCtlKeysSpec extends AnyWordSpec with Matchers {

  private val teamHex = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f"

  /** Robot 1's key from the team key above: the vector `robot-key-1` of docs/protocol.md 6.7. */
  private val robot1Hex = "d50faec98cd1be71f7448262e12d46bedeffc984c9b79c928b3afded70791be1"

  private final case class Run(code: Int, out: Vector[String], err: Vector[String])

  private def robotctl(args: Seq[String], env: Map[String, String] = Map.empty): Run = {
    val out = Vector.newBuilder[String]
    val err = Vector.newBuilder[String]
    val code = RobotKeys.run(args.drop(1), env.get, out += _, err += _, ConfigFactory.empty())
    args.headOption shouldBe Some("keys")
    Run(code, out.result(), err.result())
  }

  "robotctl keys" should {
    "print each robot's derived key from the environment's team key, never the team key" in {
      val run = robotctl(Seq("keys", "1", "2"), Map(RobotCtl.TeamKeyVariable -> teamHex))
      run.code shouldBe RobotCtl.ExitOk
      run.out.head shouldBe s"robot 1 key $robot1Hex"
      run.out should have size 2
      run.out(1) should startWith("robot 2 key ")
      run.out(1).stripPrefix("robot 2 key ") should not be robot1Hex
      (run.out ++ run.err).mkString should not include teamHex
    }
    "read the team key from the config file before the environment, as the gateway does" in {
      val file = Files.createTempFile("robotctl-keys", ".conf")
      try {
        Files.writeString(file, s"""naogateway.signing.key = "$teamHex"""")
        val run = robotctl(Seq("keys", "--config", file.toString, "1"),
          Map(RobotCtl.TeamKeyVariable -> ("ff" + teamHex.drop(2))))
        run shouldBe Run(RobotCtl.ExitOk, Vector(s"robot 1 key $robot1Hex"), Vector.empty)
      } finally Files.delete(file)
    }
    "refuse a missing or bad team key, naming its length only, and a wrong command line" in {
      val missing = robotctl(Seq("keys", "1"))
      missing.code shouldBe RobotCtl.ExitFailed
      missing.err.mkString should include(RobotCtl.TeamKeyVariable)
      val short = robotctl(Seq("keys", "1"), Map(RobotCtl.TeamKeyVariable -> "00112233"))
      short.code shouldBe RobotCtl.ExitFailed
      short.out shouldBe empty
      short.err.mkString should (include("at least 16 bytes") and not include "00112233")
      robotctl(Seq("keys")).code shouldBe RobotCtl.ExitUsage
      robotctl(Seq("keys", "one"), Map(RobotCtl.TeamKeyVariable -> teamHex)).code shouldBe RobotCtl.ExitUsage
    }
    "be reached from the command line without a gateway" in {
      val out = Vector.newBuilder[String]
      RobotCtl.run(Seq("keys", "1"), Map(RobotCtl.TeamKeyVariable -> teamHex).get, out += _, _ => ()) shouldBe
        RobotCtl.ExitOk
      out.result().size shouldBe 1
    }
  }
}
