package naogateway.gateway

import java.net.{InetAddress, InetSocketAddress}
import java.util.concurrent.atomic.AtomicReference

import org.slf4j.{Logger, LoggerFactory}

import naogateway.transport.RateLimitedLog

/** Rejected datagrams counted by kind (the closed set [[Rejection]]) and, when the sender is known, by its IP address:
  * the one ledger of rejections, immutable, so an actor keeps it as state and tests read it without actors. Both maps
  * are bounded: the kinds are a closed set, and addresses beyond `maxSources` share one counter ("other addresses").
  * Whether a count deserves a warning is [[RateLimitedLog]]'s rule, per kind, so a flood cannot flood the log.
  */
private[naogateway] final case class RejectionLedger(
    counts: Map[Rejection, Long] = Map.empty,
    bySource: Map[InetAddress, Long] = Map.empty,
    otherSources: Long = 0L,
    maxSources: Int = RejectionLedger.SourceAddresses
) {

  /** How many datagrams of `kind` were rejected. */
  def apply(kind: Rejection): Long = counts.getOrElse(kind, 0L)

  /** The ledger with `times` more rejections of `kind`, from `source` when the sender is known. */
  def count(kind: Rejection, source: Option[InetAddress] = None, times: Long = 1L): RejectionLedger = {
    val counted = copy(counts = counts.updated(kind, apply(kind) + times))
    source match {
      case None => counted
      case Some(address) =>
        bySource.get(address) match {
          case Some(n)                            => counted.copy(bySource = bySource.updated(address, n + times))
          case None if bySource.size < maxSources => counted.copy(bySource = bySource.updated(address, times))
          case None                               => counted.copy(otherSources = otherSources + times)
        }
    }
  }

  /** Whether going from `before` to this ledger passed a count of `kind` that is logged (1st, 10th, 100th, ...). */
  def warningDue(before: RejectionLedger, kind: Rejection): Boolean =
    RateLimitedLog.dueBetween(before(kind), apply(kind))

  /** The counts by kind name, as the figures show them. */
  def byKind: Map[String, Long] = counts.map { case (k, n) => k.name -> n }

  /** The counts by source address, the addresses past the bound under "other addresses". */
  def sources: Map[String, Long] = {
    val each = bySource.map { case (a, n) => a.getHostAddress -> n }
    if (otherSources > 0) each.updated(RejectionLedger.OtherSources, otherSources) else each
  }
}

/** The ledger's bound, and the ledger shared by the robot port's reader and the gateway actor. */
private[naogateway] object RejectionLedger {

  /** Source addresses whose rejections are counted one by one; the rest are counted together. */
  val SourceAddresses: Int = 64

  /** The key the addresses past [[SourceAddresses]] are counted under. */
  val OtherSources: String = "other addresses"

  /** One ledger written by two threads (the port's reader and the gateway), so it is swapped atomically. A warning
    * names the kind only; the sender and its values go to the debug log, so nothing a sender chooses can make the log
    * grow faster.
    */
  private[naogateway] final class Shared(log: Logger = LoggerFactory.getLogger("naogateway.gateway.Gateway")) {
    private val ledger = new AtomicReference(RejectionLedger())

    /** Counts `times` rejections of `kind` from `from`; warns when due; `detail` is built for the debug log only. */
    def count(kind: Rejection, from: InetSocketAddress, detail: => String = "", times: Long = 1L): Unit = {
      val source = Some(from.getAddress)
      val before = ledger.getAndUpdate(_.count(kind, source, times))
      val after = before.count(kind, source, times)
      if (after.warningDue(before, kind)) log.warn("Refused datagram: {} ({} so far)", kind.name, after(kind))
      if (log.isDebugEnabled) log.debug("Refused datagram from {}: {} {}", from, kind.name, detail)
    }

    /** The ledger as it stands. */
    def current: RejectionLedger = ledger.get
  }
}
