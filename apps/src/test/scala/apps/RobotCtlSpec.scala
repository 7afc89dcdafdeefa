package apps

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

import naogateway.wire.RpcValue

class RobotCtlSpec extends AnyWordSpec with Matchers {
  "robotctl's command line" should {
    "read status, call with typed parameters, and watch with a default duration" in {
      RobotCtl.parse(Seq("status")) shouldBe Right(RobotCtl.Request.Status)
      RobotCtl.parse(Seq("call", "2", "motion", "head", "0.5", "-0.2")) shouldBe
        Right(RobotCtl.Request.Call(2, "motion", "head", Vector(RpcValue.Number(0.5f), RpcValue.Number(-0.2f))))
      RobotCtl.parse(Seq("call", "1", "speech", "say", "hello")) shouldBe
        Right(RobotCtl.Request.Call(1, "speech", "say", Vector(RpcValue.Text("hello"))))
      RobotCtl.parse(Seq("watch", "3")) shouldBe Right(RobotCtl.Request.Watch(3, 10))
      RobotCtl.parse(Seq("watch", "3", "5")) shouldBe Right(RobotCtl.Request.Watch(3, 5))
    }
    "say clearly what is wrong" in {
      RobotCtl.parse(Seq("call", "x", "m", "n")) shouldBe Left("robot id 'x' is not a number")
      RobotCtl.parse(Seq("watch", "1", "-4")) shouldBe Left("'-4' is not a number of seconds")
      RobotCtl.parse(Seq("dance")) shouldBe Left(RobotCtl.usage)
      RobotCtl.parse(Nil) shouldBe Left(RobotCtl.usage)
    }
  }
}
