package naogateway.gateway.robot

import naogateway.wire.ActuatorGroup

/** The order in which everything for one robot leaves: the pure core of `NoResponseActor`, the robot's one sender.
  *
  * Rules: a call of a slot supersedes every older call of that slot still waiting, and every older replaceable one in
  * flight (a target such as a walk's velocities or the head's angles: it gets no more retries and its held datagrams
  * are withdrawn); a stop or a posture once sent is never superseded: the robot carries it out, and its caller keeps
  * its answer; at most `maxInFlight` calls are in flight, later ones wait in arrival order, at most `maxWaiting` of
  * them; a safety call never waits. So within a slot the robot gets calls in the order they were given, and nothing
  * older follows a newer one: no walk after a stop.
  */
private[naogateway] final case class CommandOrder[A] private (
    inFlight: Vector[CommandOrder.Entry[A]],
    waiting: Vector[CommandOrder.Entry[A]],
    maxInFlight: Int,
    maxWaiting: Int
) {
  import CommandOrder._

  /** Takes call `e`: what it supersedes, then whether it leaves now, waits (no step) or is refused. */
  def submit(e: Entry[A]): (CommandOrder[A], Vector[Step[A]]) = {
    val (sameFlying, otherFlying) =
      e.slot.fold((Vector.empty[Entry[A]], inFlight))(s => inFlight.partition(x => x.replaceable && x.slot.contains(s)))
    val (sameWaiting, otherWaiting) =
      e.slot.fold((Vector.empty[Entry[A]], waiting))(s => waiting.partition(_.slot.contains(s)))
    val superseded =
      sameFlying.map(Superseded(_, wasInFlight = true)) ++ sameWaiting.map(Superseded(_, wasInFlight = false))
    val rest = copy(inFlight = otherFlying, waiting = otherWaiting)
    if (e.safety || (rest.inFlight.size < maxInFlight && rest.waiting.isEmpty))
      (rest.copy(inFlight = rest.inFlight :+ e), superseded :+ Transmit(e))
    // A refused call changes nothing: superseding its slot's calls for a call that never goes would leave the slot
    // without either, and a call in flight withdrawn here would free room no admission follows (a waiting stop stuck).
    else if (rest.waiting.size >= maxWaiting) (this, Vector(Refused(e)))
    else {
      // Calls superseded above may have freed in-flight room: the oldest waiting ones go first, `e` after them.
      val (admitted, steps) = rest.copy(waiting = rest.waiting :+ e).admit
      (admitted, superseded ++ steps)
    }
  }

  /** Call `key` has ended (answered, timed out, dropped, or given up waiting): it leaves, waiting calls take its room.
    */
  def complete(key: Long): (CommandOrder[A], Vector[Step[A]]) =
    copy(inFlight = inFlight.filterNot(_.key == key), waiting = waiting.filterNot(_.key == key)).admit

  /** The call in flight whose payload satisfies `p`. */
  def findInFlight(p: A => Boolean): Option[Entry[A]] = inFlight.find(e => p(e.payload))

  /** The call in flight with `key`. */
  def inFlightCall(key: Long): Option[Entry[A]] = inFlight.find(_.key == key)

  /** Calls `keys` have ended at once: they leave together before any waiting call takes their room. */
  def completeAll(keys: Set[Long]): (CommandOrder[A], Vector[Step[A]]) =
    copy(inFlight = inFlight.filterNot(e => keys(e.key)), waiting = waiting.filterNot(e => keys(e.key))).admit

  /** The call with `key`, in flight or waiting. */
  def find(key: Long): Option[Entry[A]] = inFlight.find(_.key == key).orElse(waiting.find(_.key == key))

  /** Replaces the payload of the call with `key`, in flight or waiting. */
  def updated(key: Long, payload: A): CommandOrder[A] = {
    def swap(v: Vector[Entry[A]]) = v.map(e => if (e.key == key) e.copy(payload = payload) else e)
    copy(inFlight = swap(inFlight), waiting = swap(waiting))
  }

  /** Every call, in flight then waiting, and an order without any. */
  def drained: (CommandOrder[A], Vector[Entry[A]], Vector[Entry[A]]) =
    (copy(inFlight = Vector.empty, waiting = Vector.empty), inFlight, waiting)

  private def admit: (CommandOrder[A], Vector[Step[A]]) = {
    val room = math.max(0, maxInFlight - inFlight.size)
    val (go, stay) = waiting.splitAt(room)
    (copy(inFlight = inFlight ++ go, waiting = stay), go.map(Transmit(_)))
  }
}

/** Entries and steps of the command order. */
private[naogateway] object CommandOrder {

  /** A call: its key (its first call id), its slot, whether it is a safety call, what the owner keeps with it, and
    * whether a newer call of its slot replaces it (targets do; a stop or a posture does not).
    */
  final case class Entry[A](key: Long, slot: Option[ActuatorGroup], safety: Boolean, payload: A,
      replaceable: Boolean = true)

  /** What the owner must do. */
  sealed trait Step[A] extends Product with Serializable

  /** Send the call now. */
  final case class Transmit[A](entry: Entry[A]) extends Step[A]

  /** Answer the call's caller "superseded"; one in flight also loses its retries and its held datagrams. */
  final case class Superseded[A](entry: Entry[A], wasInFlight: Boolean) extends Step[A]

  /** The waiting line is full: answer the caller "overloaded". */
  final case class Refused[A](entry: Entry[A]) extends Step[A]

  /** An empty order with room for `maxInFlight` calls in flight and `maxWaiting` waiting. */
  def empty[A](maxInFlight: Int, maxWaiting: Int): CommandOrder[A] = {
    require(maxInFlight >= 1 && maxWaiting >= 0, "room for at least one call in flight")
    CommandOrder(Vector.empty, Vector.empty, maxInFlight, maxWaiting)
  }
}
