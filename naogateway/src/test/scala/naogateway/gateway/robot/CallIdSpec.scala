package naogateway.gateway.robot

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** Call ids: the owner in the two top bits, a 30-bit counter that wraps, and replies routed by the id alone. */
class CallIdSpec extends AnyWordSpec with Matchers {

  "A call id" should {
    "carry its owner in the two top bits and its counter in the lower 30 (docs/architecture.md 5)" in {
      CallId(CallId.Owner.Response, 5) shouldBe 5L
      CallId(CallId.Owner.Heartbeat, 5) shouldBe 0x80000005L
      CallId(CallId.Owner.StatusPoll, 5) shouldBe 0xc0000005L
      for (owner <- CallId.Owner.all; count <- Seq(0L, 1L, 12345L, CallId.Mask)) {
        val id = CallId(owner, count)
        CallId.ownerOf(id) shouldBe Some(owner)
        CallId.count(id) shouldBe count
        id should be <= 0xffffffffL
      }
    }
    "count up per owner and wrap within the owner's range" in {
      CallId.next(CallId.Owner.Heartbeat, CallId(CallId.Owner.Heartbeat, 7)) shouldBe CallId(CallId.Owner.Heartbeat, 8)
      CallId.next(CallId.Owner.Response, CallId.Mask) shouldBe 0L
      CallId.next(CallId.Owner.StatusPoll, CallId.Mask) shouldBe 0xc0000000L
      CallId(CallId.Owner.Response, CallId.Mask + 3) shouldBe 2L
    }
    "name no owner for the unused tag 1 or an id wider than 32 bits" in {
      CallId.ownerOf(0x40000000L) shouldBe None
      CallId.ownerOf(0x100000000L) shouldBe None
    }
    "start from a counter within 30 bits" in {
      all(Seq.fill(100)(CallId.randomStart())) should (be >= 0L and be <= CallId.Mask)
    }
  }
}
