package naogateway.wire

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** docs/protocol.md §7.2: the postures a robot reports and the ones a caller may ask for. */
class PostureSpec extends AnyWordSpec with Matchers {

  "Posture.reported" should {
    "know every posture of §7.2 by its wire name" in {
      Posture.known.map(_.name) shouldBe Vector("sit", "stand", "crouch", "walking", "moving", "fallen")
      Posture.known.foreach(p => Posture.reported(p.name) shouldBe p)
    }

    "keep a name it does not know, as reported, instead of failing" in {
      val p = Posture.reported("kneeling")
      p shouldBe a[Posture.Unknown]
      p.name shouldBe "kneeling"
      Posture.reported("Sit") shouldBe a[Posture.Unknown] // names are exact, as on the wire
    }
  }

  "Posture.target" should {
    "accept sit, stand and crouch" in {
      Posture.targets.map(_.name) shouldBe Vector("sit", "stand", "crouch")
      Posture.target("crouch") shouldBe Right(Posture.Crouch)
    }

    "refuse a reported-only or unknown posture with the names it takes" in {
      Posture.target("walking") shouldBe Left("unknown posture 'walking' (sit, stand, crouch)")
      Posture.target("dance") shouldBe Left("unknown posture 'dance' (sit, stand, crouch)")
    }
  }
}
