package naogateway.api

import java.net.InetAddress

import naogateway.wire.gamecontroller.ReturnStatus

/** What the monitor role heard: one robot's forwarded status message. */
final case class ForwardedStatus(from: InetAddress, status: ReturnStatus, atNanos: Long)
