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
