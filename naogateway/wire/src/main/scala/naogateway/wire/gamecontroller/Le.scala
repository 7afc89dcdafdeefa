package naogateway.wire.gamecontroller

import scala.collection.immutable.ArraySeq

/** Little-endian reads from a position; callers check the size first, so reads stay in bounds. */
private[gamecontroller] final class LeReader(data: Array[Byte], private var position: Int) {
  def u8(): Int = {
    val value = data(position) & 0xff
    position += 1
    value
  }
  def u16(): Int = {
    val low = u8()
    low | (u8() << 8)
  }
  def i16(): Int = u16().toShort.toInt
  def u32(): Long = {
    val low = u16().toLong
    low | (u16().toLong << 16)
  }
  def f32(): Float = java.lang.Float.intBitsToFloat(u32().toInt)
  def take(n: Int): ArraySeq[Byte] = {
    val copy = java.util.Arrays.copyOfRange(data, position, position + n)
    position += n
    ArraySeq.unsafeWrapArray(copy)
  }
}

/** Little-endian writes into a buffer of the packet's exact size; i16 values go out as their two's complement. */
private[gamecontroller] final class LeWriter(size: Int) {
  val out: Array[Byte] = new Array[Byte](size)
  private var position = 0
  def u8(value: Int): Unit = {
    out(position) = value.toByte
    position += 1
  }
  def u16(value: Int): Unit = {
    u8(value)
    u8(value >> 8)
  }
  def u32(value: Long): Unit = {
    u16((value & 0xffff).toInt)
    u16(((value >>> 16) & 0xffff).toInt)
  }
  def f32(value: Float): Unit = u32(java.lang.Float.floatToRawIntBits(value).toLong & 0xffffffffL)
  def flag(value: Boolean): Unit = u8(if (value) 1 else 0)
  def raw(bytes: Array[Byte]): Unit = {
    System.arraycopy(bytes, 0, out, position, bytes.length)
    position += bytes.length
  }
}

/** The width of one number on the wire with the range it holds: a layout names widths, so where versions differ in a
  * field's width the difference is data, and reading, writing and the range check follow from it.
  */
private[gamecontroller] sealed abstract class Width(val bytes: Int, val min: Long, val max: Long) {

  /** Reads one number of this width. */
  def read(r: LeReader): Long

  /** Writes one number of this width (a signed one as its two's complement). */
  def write(w: LeWriter, value: Long): Unit
}

/** The widths of the GameController's numbers. */
private[gamecontroller] object Width {

  /** One unsigned byte. */
  case object U8 extends Width(1, 0L, 0xffL) {
    def read(r: LeReader): Long = r.u8().toLong
    def write(w: LeWriter, value: Long): Unit = w.u8(value.toInt)
  }

  /** Two bytes, unsigned. */
  case object U16 extends Width(2, 0L, 0xffffL) {
    def read(r: LeReader): Long = r.u16().toLong
    def write(w: LeWriter, value: Long): Unit = w.u16(value.toInt)
  }

  /** Two bytes, signed. */
  case object I16 extends Width(2, Short.MinValue.toLong, Short.MaxValue.toLong) {
    def read(r: LeReader): Long = r.i16().toLong
    def write(w: LeWriter, value: Long): Unit = w.u16(value.toInt)
  }

  /** Four bytes, unsigned. */
  case object U32 extends Width(4, 0L, 0xffffffffL) {
    def read(r: LeReader): Long = r.u32()
    def write(w: LeWriter, value: Long): Unit = w.u32(value)
  }

  /** The unsigned width of a version field of `bytes` bytes (1, 2 or 4). */
  def unsigned(bytes: Int): Width = Seq(U8, U16, U32).find(_.bytes == bytes).getOrElse(U32)
}
