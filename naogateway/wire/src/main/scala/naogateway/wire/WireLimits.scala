package naogateway.wire

/** Fixed limits of the robot's link (docs/protocol.md §2, §10, §11). */
object WireLimits {

  /** The GS1500M module's buffer: no datagram to or from a robot may be larger. */
  val MaxDatagramBytes: Int = 1400

  /** First two bytes of every FU-Remote frame (operation 42, big-endian). */
  val FumanoidsOperation: Int = 42

  /** Sequence numbers and ACKs of the secure stream stay below this, so they never read `00 2A` or `RG`. */
  val StreamSequenceLimit: Int = 42
}
