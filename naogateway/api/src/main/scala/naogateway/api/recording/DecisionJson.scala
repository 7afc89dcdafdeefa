package naogateway.api.recording

import java.net.InetSocketAddress

import naogateway.api.{GameStateUpdated, LinkQualityChanged, RobotOffline, RobotOnline, RobotRestarted}
import naogateway.wire.{MessageContents, RpcCall, RpcReply}

/** The decisions as JSON objects, one per message; field names are the code's names: the recording's
  * `/gateway/decisions` channel, and the live feed's channel of the same name (apps.web.FoxgloveFeed).
  */
object DecisionJson {

  /** `a` as `address:port` text (empty for none). */
  def address(a: InetSocketAddress): String =
    if (a == null) "" else s"${Option(a.getAddress).fold(a.getHostString)(_.getHostAddress)}:${a.getPort}"

  private def quote(s: String): String = {
    val b = new StringBuilder("\"")
    s.foreach {
      case '"'          => b.append("\\\"")
      case '\\'         => b.append("\\\\")
      case c if c < ' ' => b.append(f"\\u${c.toInt}%04x")
      case c            => b.append(c)
    }
    b.append('"').toString
  }

  private def obj(fields: (String, String)*): String =
    fields.map { case (k, v) => s"${quote(k)}:$v" }.mkString("{", ",", "}")

  private def opt[A](a: Option[A])(f: A => String): String = a.fold("null")(f)

  /** Robot `robotId`'s RPC reply, recorded at `time`. */
  def reply(robotId: Int, reply: RpcReply, time: Long): String =
    obj(
      "decision" -> quote("reply"),
      "gatewayTimeNs" -> time.toString,
      "robotId" -> robotId.toString,
      "callId" -> opt(reply.callId)(_.toString),
      "outcome" -> quote(reply.result.fold(e => s"error: $e", _ => "ok"))
    )

  /** `decision`, made at `time` (Unix nanoseconds). */
  def of(decision: Decision, time: Long): String = {
    val t = "gatewayTimeNs" -> time.toString
    decision match {
      case Decision.Published(event) =>
        event match {
          case RobotOnline(id, at) =>
            obj("decision" -> quote("robot-online"), t, "robotId" -> id.toString, "address" -> quote(address(at)))
          case RobotOffline(id, reason) =>
            obj("decision" -> quote("robot-offline"), t, "robotId" -> id.toString, "reason" -> quote(reason))
          case RobotRestarted(id, bootId, resynced) =>
            obj("decision" -> quote("robot-restarted"), t, "robotId" -> id.toString,
              "bootId" -> opt(bootId)(_.toString),
              "resynced" -> resynced.map(quote).mkString("[", ",", "]"))
          case LinkQualityChanged(id, quality) =>
            obj("decision" -> quote("link-quality"), t, "robotId" -> id.toString, "quality" -> quote(quality.name))
          case GameStateUpdated(data) =>
            obj("decision" -> quote("game-state"), t, "state" -> quote(data.gameState.toString),
              "version" -> data.version.number.toString)
          case other => // keep-alives are on the status channels; an event added later is still recorded by name
            obj("decision" -> quote(other.productPrefix), t)
        }
      case Decision.Outgoing(robotId, priority, outcome, bytes) =>
        val call = MessageContents.decodeFrame(bytes).toOption.flatMap(_._2.rpcRequest).map(RpcCall.fromProto)
        obj(
          "decision" -> quote("send"),
          t,
          "robotId" -> robotId.toString,
          "priority" -> quote(priority.name),
          "outcome" -> quote(outcome),
          "bytes" -> bytes.length.toString,
          "call" -> opt(call)(c => quote(c.name)),
          "callId" -> opt(call.flatMap(_.callId))(_.toString)
        )
      case Decision.Gate(open, reading) =>
        val state = reading match {
          case naogateway.api.GameReading.Known(s, _)               => s.toString
          case naogateway.api.GameReading.HeaderOnly(s, version, _) => s"$s (shared header of version $version)"
          case naogateway.api.GameReading.Unreadable(reason)        => s"unreadable: $reason"
          case naogateway.api.GameReading.Opening(s, leftMillis, _) => s"$s (opening in $leftMillis ms)"
          case naogateway.api.GameReading.NotHeard                  => "not heard"
        }
        obj("decision" -> quote(if (open) "gate-open" else "gate-closed"), t, "state" -> quote(state))
      case Decision.Budget(out, in, limit, queued) =>
        obj(
          "decision" -> quote("budget"),
          t,
          "outBytesLastSecond" -> out.toString,
          "inBytesLastSecond" -> in.toString,
          "limitBytesPerSecond" -> limit.toString,
          "queued" -> obj(queued.toSeq.sortBy(_._1).map { case (k, v) => k -> v.toString }: _*)
        )
    }
  }
}
