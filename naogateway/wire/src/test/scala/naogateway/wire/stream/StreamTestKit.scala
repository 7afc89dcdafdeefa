package naogateway.wire.stream

import java.nio.charset.StandardCharsets

import scala.concurrent.duration._

import SecureStream._

/** Small helpers for driving endpoints by hand in tests. */
object StreamTestKit {

  def ms(n: Long): Long = n.millis.toNanos

  def bytes(text: String): Array[Byte] = text.getBytes(StandardCharsets.UTF_8)

  def text(payload: Array[Byte]): String = new String(payload, StandardCharsets.UTF_8)

  def segment(seq: Int, ack: Int, payload: String = ""): Array[Byte] =
    Array(seq.toByte, ack.toByte) ++ bytes(payload)

  def transmits(step: Step): Vector[Vector[Int]] =
    step.outputs.collect { case Transmit(d) => d.toVector.map(_ & 0xff) }

  def headers(step: Step): Vector[(Int, Int)] = transmits(step).map(d => (d(0), d(1)))

  def delivered(step: Step): Vector[String] = step.outputs.collect { case Deliver(p) => text(p) }

  def acknowledged(step: Step): Vector[Long] = step.outputs.collect { case Acknowledged(id) => id }

  def expired(step: Step): Vector[Long] = step.outputs.collect { case Expired(id) => id }

  def datagrams(step: Step): Vector[Array[Byte]] = step.outputs.collect { case Transmit(d) => d }

  implicit final class SendOps(private val state: SecureStream) extends AnyVal {

    /** A send that the test expects to be accepted. */
    def offer(payload: String, id: Long, now: Long, deadline: Option[Long] = None): Step =
      state.send(bytes(payload), id, deadline, now) match {
        case Right(step)   => step
        case Left(refusal) => throw new AssertionError(s"unexpected refusal: ${refusal.describe}")
      }
  }
}
