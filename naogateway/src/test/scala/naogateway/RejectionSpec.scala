package naogateway

import java.net.InetAddress

import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

class RejectionSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {

  private def address(i: Int): InetAddress = InetAddress.getByAddress(Array[Byte](10, (i >> 16).toByte, (i >> 8).toByte, i.toByte))

  "The rejection ledger" should {
    "stay bounded by the kinds and the address limit however many senders there are" in {
      forAll(Gen.listOfN(2000, Gen.zip(Gen.oneOf(Rejection.all), Gen.choose(0, 100000)))) { events =>
        val ledger = events.foldLeft(RejectionLedger.empty(8)) { case (l, (k, a)) => l.record(k, Some(address(a)))._1 }
        ledger.byAddress.size should be <= 8
        ledger.byKind.size should be <= Rejection.all.size
        ledger.total shouldBe events.size.toLong
        ledger.byAddress.values.sum + ledger.otherAddresses shouldBe events.size.toLong
      }
    }

    "warn about 100,000 refusals of one kind in six lines" in {
      val (_, warnings) = (1 to 100000).foldLeft((RejectionLedger.empty(), 0)) { case ((l, w), i) =>
        val (next, warn) = l.record(Rejection.BadProtobuf, Some(address(i)))
        (next, if (warn) w + 1 else w)
      }
      warnings shouldBe 6
    }

    "name every kind once" in {
      Rejection.all.map(_.name).distinct.size shouldBe Rejection.all.size
    }
  }

  "Trusted sources" should {
    "match addresses inside their subnets only" in {
      val trusted = TrustedSources(Vector(Subnet.parse("10.0.0.0/24").toOption.get, Subnet.parse("192.168.1.7").toOption.get))
      trusted.trusts(InetAddress.getByName("10.0.0.99")) shouldBe true
      trusted.trusts(InetAddress.getByName("10.0.1.1")) shouldBe false
      trusted.trusts(InetAddress.getByName("192.168.1.7")) shouldBe true
      trusted.trusts(InetAddress.getByName("192.168.1.8")) shouldBe false
      trusted.trusts(InetAddress.getByName("::1")) shouldBe false
      Subnet.parse("127.0.0.0/8").toOption.get.contains(InetAddress.getByName("127.0.0.42")) shouldBe true
      Subnet.parse("10.0.0.0/20").toOption.get.contains(InetAddress.getByName("10.0.15.255")) shouldBe true
      Subnet.parse("10.0.0.0/20").toOption.get.contains(InetAddress.getByName("10.0.16.0")) shouldBe false
    }

    "refuse names and bad prefixes with a clear error, and trust anyone when none is configured" in {
      Subnet.parse("gamecontroller.local").isLeft shouldBe true
      Subnet.parse("10.0.0.0/33").left.toOption.get should include("0 to 32")
      TrustedSources(Vector.empty).trusts(InetAddress.getByName("8.8.8.8")) shouldBe true
      TrustedSources(Vector.empty).configured shouldBe false
    }
  }
}
