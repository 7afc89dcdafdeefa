package naogateway.gateway.robot

import scala.collection.mutable

/** Bytes sent or received over a sliding window, exact to the datagram (not bucketed), so a budget holds in every
  * window.
  */
private[naogateway] final class TrafficMeter(windowNanos: Long) {
  private val times = mutable.ArrayDeque.empty[Long]
  private val sizes = mutable.ArrayDeque.empty[Int]
  private var sum = 0L
  private var datagramCount = 0L

  private def expire(now: Long): Unit =
    while (times.nonEmpty && times.head <= now - windowNanos) {
      times.removeHead()
      sum -= sizes.removeHead()
    }

  /** Counts `bytes` at `now`. */
  def record(now: Long, bytes: Int): Unit = record(now, bytes, 1)

  /** Counts `datagrams` datagrams of `bytes` together at `now`. */
  def record(now: Long, bytes: Int, datagrams: Int): Unit = {
    expire(now)
    times.append(now)
    sizes.append(bytes)
    sum += bytes
    datagramCount += datagrams
  }

  /** Bytes within the window ending at `now`. */
  def inWindow(now: Long): Long = { expire(now); sum }

  /** Whether `bytes` more at `now` keep the window at or under `limit`. */
  def fits(now: Long, bytes: Int, limit: Long): Boolean = inWindow(now) + bytes <= limit

  /** The earliest time at which `bytes` more fit under `limit` (now, if they fit already). */
  def fitsAt(now: Long, bytes: Int, limit: Long): Long = {
    expire(now)
    var excess = sum + bytes - limit
    if (excess <= 0) now
    else {
      val it = times.iterator.zip(sizes.iterator)
      var at = now
      while (excess > 0 && it.hasNext) {
        val (t, size) = it.next()
        excess -= size
        at = t + windowNanos
      }
      at
    }
  }

  /** Datagrams counted since creation. */
  def totalDatagrams: Long = datagramCount
}
