package naogateway.gateway.robot

/** Call ids (`uint32`, protocol.md 6.6; docs/architecture.md 5): the two top bits name the owner of the call, the lower
  * 30 bits count up per owner and wrap, so a reply reaches its owner by its id alone.
  */
private[naogateway] object CallId {

  /** The counting part of a call id: the lower 30 bits. */
  val Mask: Long = 0x3fffffffL

  /** Who gave a call its id; `tag` is the value of the id's two top bits. */
  sealed abstract class Owner(val tag: Int)

  object Owner {

    /** `ResponseActor`: every RPC call of the robot actor. */
    case object Response extends Owner(0)

    /** `HeartBeatActor`'s probes. */
    case object Heartbeat extends Owner(2)

    /** The ZeroMQ link's own status polls (answered inside the link). */
    case object StatusPoll extends Owner(3)

    val all: Seq[Owner] = Seq(Response, Heartbeat, StatusPoll)
  }

  /** The id of `owner` with counter `count` (wrapped into 30 bits). */
  def apply(owner: Owner, count: Long): Long = (owner.tag.toLong << 30) | (count & Mask)

  /** The id after `last` for `owner`: the counter of `last` plus one, wrapped. */
  def next(owner: Owner, last: Long): Long = CallId(owner, (last & Mask) + 1)

  /** The counting part of `id`. */
  def count(id: Long): Long = id & Mask

  /** The owner named by the top bits of `id`; None for a tag nobody owns or an id wider than 32 bits. */
  def ownerOf(id: Long): Option[Owner] = Owner.all.find(_.tag.toLong == (id >>> 30))

  /** A random counter to start from, so that a late reply from before a restart matches nothing new. */
  def randomStart(): Long = java.util.concurrent.ThreadLocalRandom.current().nextLong(Mask)
}
