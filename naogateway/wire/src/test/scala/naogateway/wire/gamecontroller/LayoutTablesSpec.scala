package naogateway.wire.gamecontroller

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** The tables that say where versions differ: they must add up to what each version is on the wire. */
class LayoutTablesSpec extends AnyWordSpec with Matchers {

  private def when(present: Boolean, bytes: Int): Int = if (present) bytes else 0

  /** The size a 2014 layout's table gives: header, version field, then what the decoder reads, field by field. */
  private def size(l: Layout2014): Int = {
    val player = 2 * l.playerField.bytes
    val team = 3 + when(l.goalColour, 1) + when(l.shotsAndCoach, 1 + 2 + TeamInfo.CoachMessageBytes + player) +
      TeamInfo.PlayerSlots * player
    4 + l.version.versionBytes + when(l.packetNumber, 1) + 6 + 2 + l.secsRemaining.bytes +
      when(l.secondaryTime, 2) + 2 * team
  }

  "The 2014 layout table" should {
    "give each version's exact packet size, and cover versions 8 and 7 only" in {
      Seq(Layouts2014.V8, Layouts2014.V7).foreach { l =>
        withClue(l.version) { size(l) shouldBe l.version.packetBytes }
      }
      Layouts2014.of(GameControlVersion.V8) shouldBe Some(Layouts2014.V8)
      Layouts2014.of(GameControlVersion.V7) shouldBe Some(Layouts2014.V7)
      Layouts2014.of(GameControlVersion.V12) shouldBe None
      Layouts2014.of(GameControlVersion.V19) shouldBe None
      Layouts2014.of(GameControlVersion.V20) shouldBe None
    }
  }

  "The version field" should {
    "have for every version a width of its versionBytes, holding its number" in {
      GameControlVersion.all.foreach { v =>
        val width = GameControllerCodec.versionField(v)
        width.bytes shouldBe v.versionBytes
        v.number.toLong should (be >= width.min and be <= width.max)
      }
      GameControlVersion.all.map(v => v.number -> v.versionBytes) shouldBe Seq(20 -> 1, 19 -> 1, 12 -> 2, 8 -> 1,
        7 -> 4)
    }
  }

  "Every width" should {
    "write and read back its least and greatest value in exactly its bytes" in {
      Seq(Width.U8, Width.U16, Width.I16, Width.U32).foreach { width =>
        Seq(width.min, width.max).foreach { value =>
          val w = new LeWriter(width.bytes)
          width.write(w, value)
          width.read(new LeReader(w.out, 0)) shouldBe value
        }
      }
    }
  }
}
