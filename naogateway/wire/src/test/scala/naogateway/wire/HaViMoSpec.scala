package naogateway.wire

import org.scalacheck.Gen
import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec
import org.scalatestplus.scalacheck.ScalaCheckPropertyChecks

class HaViMoSpec extends AnyWordSpec with Matchers with ScalaCheckPropertyChecks {
  import MessageGenerators._

  "HaViMo region records" should {
    "be 16 bytes each, little-endian, in the camera's field order" in {
      val r = HaViMoRegion(index = 1, colour = 2, pixels = 0x0304, sumX = 0x05060708L, sumY = 0x090a0b0cL,
        maxX = 13, minX = 14, maxY = 15, minY = 16)
      HaViMo.encodeRegions(Seq(r)).map(_.toSeq) shouldBe Right(
        Seq(1, 2, 4, 3, 8, 7, 6, 5, 12, 11, 10, 9, 13, 14, 15, 16).map(_.toByte)
      )
    }
    "give the centre of mass as sums over pixels" in {
      val r = HaViMoRegion(1, 1, pixels = 4, sumX = 200, sumY = 100, 60, 40, 30, 20)
      (r.centreX, r.centreY) shouldBe ((50.0, 25.0))
    }
    "skip unused slots (index 0)" in {
      val unused = new Array[Byte](16)
      HaViMo.decodeRegions(unused) shouldBe Right(Vector.empty)
    }
    "round-trip any up to 15 regions" in {
      forAll(Gen.choose(0, 15).flatMap(Gen.listOfN(_, region))) { regions =>
        HaViMo.encodeRegions(regions).flatMap(HaViMo.decodeRegions) shouldBe Right(regions.toVector)
      }
    }
    "refuse more than 15 records and partial records" in {
      HaViMo.decodeRegions(new Array[Byte](16 * 16)).isLeft shouldBe true
      HaViMo.decodeRegions(new Array[Byte](17)).isLeft shouldBe true
      HaViMo.encodeRegions(Seq.fill(16)(HaViMoRegion(1, 0, 0, 0, 0, 0, 0, 0, 0))).isLeft shouldBe true
    }
    "never throw on arbitrary bytes" in {
      forAll(anyBytes) { bytes => noException should be thrownBy HaViMo.decodeRegions(bytes) }
    }
  }

  "HaViMo grid frames" should {
    "address cell (x, y) at x + 32y with colour in the low and count in the high nibble" in {
      val cells = new Array[Byte](768)
      cells(5 + 32 * 7) = 0x93.toByte
      val grid = HaViMo.decodeGrid(cells).toOption.get
      grid.colour(5, 7) shouldBe 3
      grid.count(5, 7) shouldBe 9
      grid.colour(7, 5) shouldBe 0
    }
    "refuse anything but 768 bytes" in {
      HaViMo.decodeGrid(new Array[Byte](767)).isLeft shouldBe true
      forAll(anyBytes) { bytes =>
        HaViMo.decodeGrid(bytes).isRight shouldBe (bytes.length == 768)
      }
    }
  }
}
