package naogateway.gateway.gamecontroller

import java.net.InetSocketAddress

/** Every GameController heard on the field (each sender of a readable control packet, by address and port), so that a
  * second one (a test GameController on the next field, a second instance on the same host: packet numbers that
  * interleave) is seen and named, and game state comes from one trusted GameController only: the one heard first, for
  * as long as it keeps sending. Pure, bounded to [[GameControllerSources.MaxSenders]] senders; the gateway holds one.
  *
  * @param heard
  *   per sender: when it was last heard (gateway clock), its last packet number, whether it is trusted
  * @param chosen
  *   the trusted sender whose packets give the game state
  */
private[naogateway] final case class GameControllerSources(
    heard: Map[InetSocketAddress, GameControllerSources.Heard] = Map.empty,
    chosen: Option[InetSocketAddress] = None
) {
  import GameControllerSources._

  /** Whether `from` has been heard within [[QuietNanos]] of `nowNanos`. */
  private def live(from: InetSocketAddress, nowNanos: Long): Boolean =
    heard.get(from).exists(h => nowNanos - h.lastNanos < QuietNanos)

  /** A readable control packet from `from`; the second value says whether its game state counts: it must be trusted,
    * and be the chosen sender, or the chosen one must have gone quiet.
    */
  def packet(from: InetSocketAddress, packetNumber: Option[Int], trusted: Boolean, nowNanos: Long)
      : (GameControllerSources, Boolean) = {
    val entry = Heard(nowNanos, packetNumber, trusted, heard.get(from).fold(1L)(_.packets + 1))
    val updated = heard.updated(from, entry)
    val bounded =
      if (updated.size <= MaxSenders) updated
      else updated - updated.filter(_._1 != from).minBy(_._2.lastNanos)._1
    val use = trusted && (chosen.contains(from) || chosen.forall(c => !live(c, nowNanos)))
    (GameControllerSources(bounded, if (use) Some(from) else chosen), use)
  }

  /** The GameControllers heard within [[QuietNanos]], beside the chosen one. */
  def others(nowNanos: Long): Vector[InetSocketAddress] =
    heard.keys.filter(a => !chosen.contains(a) && live(a, nowNanos)).toVector.sortBy(a =>
      (a.getAddress.getHostAddress, a.getPort))

  /** A warning while a GameController is heard whose state does not count: which one gives the game state and which are
    * ignored, or that none gives it because none heard is trusted. A trusted one taking over from a chosen one gone
    * quiet is no cause: its next packet makes it the chosen one.
    */
  def warnings(nowNanos: Long): Vector[String] = {
    val rest = others(nowNanos)
    def name(a: InetSocketAddress) = s"${a.getAddress.getHostAddress}:${a.getPort}"
    def listed = rest.map { a =>
      val why = if (heard(a).trusted) "trusted, ignored while the other sends" else "untrusted, ignored"
      s"${name(a)} ($why)"
    }.mkString(", ")
    chosen.filter(live(_, nowNanos)) match {
      case _ if rest.isEmpty => Vector.empty
      case Some(c) =>
        Vector(s"${rest.size + 1} GameControllers on this field: game state from ${name(c)} only; $listed")
      case None if rest.forall(a => !heard(a).trusted) =>
        val untrusted = if (rest.size == 1) s"the GameController heard, ${name(rest.head)}, is untrusted"
        else s"the ${rest.size} GameControllers heard are untrusted: ${rest.map(name).mkString(", ")}"
        Vector(s"no game state: $untrusted (naogateway.game-controller.trusted-sources)")
      case None => Vector.empty
    }
  }
}

/** Constants and entries of [[GameControllerSources]]. */
private[naogateway] object GameControllerSources {

  /** What is known of one sender. */
  final case class Heard(lastNanos: Long, packetNumber: Option[Int], trusted: Boolean, packets: Long)

  /** Senders remembered at once; the one heard longest ago makes room. */
  val MaxSenders: Int = 8

  /** A GameController not heard this long (its packets come twice a second) is gone. */
  val QuietNanos: Long = 5000000000L
}
