package naogateway.wire.gamecontroller

import scala.collection.immutable.ArraySeq

/** Why bytes are not a GameController packet, or why a value cannot be encoded as one. */
sealed trait GameControllerError extends Product with Serializable {

  /** A short text for logs. */
  def describe: String
}

/** Every way a GameController packet can be refused, each a value, never an exception. */
object GameControllerError {

  private def hex(bytes: ArraySeq[Byte]): String = bytes.map(b => f"${b & 0xff}%02X").mkString(" ")

  /** Fewer bytes than needed to read the header or the version. */
  final case class TooShort(needed: Int, found: Int) extends GameControllerError {
    def describe: String = s"GameController packet too short: needs at least $needed bytes, got $found"
  }

  /** The first four bytes are not the expected header (`RGme` or `RGrt`). */
  final case class WrongHeader(expected: String, found: ArraySeq[Byte]) extends GameControllerError {
    def describe: String = s"expected header $expected, found ${hex(found)}"
  }

  /** The version is not one this codec knows. `found` holds the raw bytes from offset 4 on (up to four), because the
    * width of the version field is itself version-specific.
    */
  final case class UnknownVersion(header: String, found: ArraySeq[Byte]) extends GameControllerError {
    def describe: String = s"$header packet of unknown version: bytes from offset 4 are ${hex(found)}"
  }

  /** The version is known but the packet does not have that version's exact size. */
  final case class WrongSize(header: String, version: Int, expected: Int, found: Int) extends GameControllerError {
    def describe: String = s"$header version $version packet must be $expected bytes, got $found"
  }

  /** A packet read by its shared header only (docs/protocol.md §10.8) whose size is outside what any version could
    * plausibly have.
    */
  final case class ImplausibleSize(header: String, version: Int, min: Int, max: Int, found: Int)
      extends GameControllerError {
    def describe: String = s"$header version $version packet of $found bytes: not $min to $max, so not read"
  }

  /** A field holds a value its type cannot carry (e.g. `firstHalf` neither 0 nor 1). */
  final case class InvalidField(field: String, value: Long) extends GameControllerError {
    def describe: String = s"invalid value $value in field $field"
  }

  /** A floating-point field holds NaN, which the GameController refuses too. */
  final case class NotANumber(field: String) extends GameControllerError {
    def describe: String = s"field $field is not a number (NaN)"
  }

  /** A field the target version has is `None`. */
  final case class MissingField(version: Int, field: String) extends GameControllerError {
    def describe: String = s"version $version needs field $field"
  }

  /** A field the target version lacks is present, and would be lost. */
  final case class UnexpectedField(version: Int, field: String) extends GameControllerError {
    def describe: String = s"version $version has no field $field"
  }

  /** A value does not fit the wire width of its field in the target version. */
  final case class OutOfRange(version: Int, field: String, value: Long, min: Long, max: Long)
      extends GameControllerError {
    def describe: String = s"field $field = $value does not fit version $version (range $min..$max)"
  }

  /** A fixed-length field (players, coach message) has the wrong number of elements. */
  final case class WrongLength(field: String, expected: Int, found: Int) extends GameControllerError {
    def describe: String = s"field $field must have $expected elements, has $found"
  }
}
