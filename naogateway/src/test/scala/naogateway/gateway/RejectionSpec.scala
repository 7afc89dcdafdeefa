package naogateway.gateway

import java.net.InetAddress

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

class RejectionSpec extends AnyWordSpec with Matchers {

  "Rejection kinds" should {
    "name every kind once" in {
      Rejection.all.map(_.name).distinct.size shouldBe Rejection.all.size
    }
  }

  "Trusted sources" should {
    "match addresses inside their subnets only" in {
      val trusted =
        TrustedSources(Vector(Subnet.parse("10.0.0.0/24").toOption.get, Subnet.parse("192.168.1.7").toOption.get))
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
