package naogateway.gateway.link

import java.util.concurrent.atomic.AtomicInteger

/** A soft bound on the messages one thread hands an actor's unbounded mailbox: the sender takes a place before each
  * message ([[tryAdd]]), the actor gives it back when it handles one ([[done]]). When the actor falls behind, the
  * sender drops (and counts) instead of letting the mailbox grow without bound.
  *
  * Soft: an actor that restarts may lose messages that held places, so it calls [[reset]] on start, and [[done]] never
  * goes below zero; the bound can then be overshot by what was in flight across the restart, never for ever.
  */
final class Backlog(val limit: Int) {
  require(limit > 0, s"a backlog limit must be positive, not $limit")
  private val waiting = new AtomicInteger

  /** Takes a place; false (and nothing taken) when `limit` messages wait already. */
  def tryAdd(): Boolean =
    if (waiting.incrementAndGet() <= limit) true
    else {
      waiting.decrementAndGet()
      false
    }

  /** Takes a place whatever the count: for a sender whose own input is bounded already. */
  def add(): Unit = waiting.incrementAndGet()

  /** One message was handled. */
  def done(): Unit = waiting.getAndUpdate(n => if (n > 0) n - 1 else 0)

  /** Forgets every place taken: the receiving actor (re)started. */
  def reset(): Unit = waiting.set(0)

  /** Messages waiting now, as far as this count knows. */
  def size: Int = waiting.get
}
