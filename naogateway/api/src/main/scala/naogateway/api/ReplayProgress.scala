package naogateway.api

/** What a replay did so far: datagrams handed to the gateway, datagrams the gateway sent and that went nowhere. */
final case class ReplayProgress(fed: Long, discarded: Long, finished: Boolean)
