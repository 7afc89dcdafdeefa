package apps.web

import java.net.{InetAddress, URI}

import scala.util.Try

/** A web origin (scheme, host, port) as a browser names it in a WebSocket handshake's `Origin` header. */
final case class WebOrigin(scheme: String, host: String, port: Int)

/** The rule every WebSocket of the web view applies to its handshake (docs/web.md, "Who may connect"): a browser's
  * handshake must come from the page's own origin or a configured one, so a page of another site open in the operator's
  * browser can neither read the feed nor switch a camera on.
  */
object WebOrigin {

  /** What the rule says of one handshake. */
  sealed trait Verdict extends Product with Serializable

  /** The handshake passes (it still needs the token when one is set). */
  case object Allowed extends Verdict

  /** The handshake is refused with 403, for `reason` (safe to log: control characters are replaced). */
  final case class Refused(reason: String) extends Verdict

  private def defaultPort(scheme: String): Int = if (scheme == "https" || scheme == "wss") 443 else 80

  /** The origin `text` names (`scheme://host[:port]`, no path), lower-cased; None for `null` or anything else. */
  def parse(text: String): Option[WebOrigin] =
    Try(new URI(text.trim)).toOption.filter(u =>
      u.getScheme != null && u.getHost != null && u.getRawUserInfo == null &&
        (u.getRawPath == null || u.getRawPath.isEmpty || u.getRawPath == "/") && u.getRawQuery == null &&
        u.getRawFragment == null).map { u =>
      val scheme = u.getScheme.toLowerCase
      WebOrigin(scheme, u.getHost.toLowerCase.stripPrefix("[").stripSuffix("]"),
        if (u.getPort < 0) defaultPort(scheme) else u.getPort)
    }.filter(o => o.scheme == "http" || o.scheme == "https")

  /** The origin of a page fetched over `scheme` from `host` (a Host header: `name[:port]`, `[v6][:port]`). */
  def ofHost(scheme: String, host: String): Option[WebOrigin] = parse(s"$scheme://${host.trim}")

  /** Whether `host` is a loopback address literal or `localhost`, decided without asking DNS (a name a stranger
    * controls could resolve to 127.0.0.1).
    */
  def loopbackLiteral(host: String): Boolean = {
    val h = host.toLowerCase.stripPrefix("[").stripSuffix("]")
    h == "localhost" || {
      val v4 = h.matches("""\d{1,3}(\.\d{1,3}){3}""")
      val v6 = h.contains(':') && h.forall(c => Character.digit(c, 16) >= 0 || c == ':' || c == '.')
      (v4 || v6) && Try(InetAddress.getByName(h).isLoopbackAddress).getOrElse(false)
    }
  }

  /** The verdict on a handshake with `origin` (its Origin header, if any) sent to `host` (its Host header) over
    * `scheme` (the request's: `ws`, `wss`, `http` or `https`), given the `allowed` origins and whether a token is set:
    *   - no Origin: allowed (not a browser: a browser sends Origin with every WebSocket handshake), on the token alone;
    *   - without a token, the page's address must be loopback (`127.x`, `localhost`, `[::1]`): a stranger's name made
    *     to point at this machine (DNS rebinding) has an origin of its own that matches its Host;
    *   - the page's own origin (the scheme and Host it was opened at) or one of `allowed`: allowed;
    *   - anything else (another site, `null`, an unreadable header): refused.
    */
  def check(origin: Option[String], host: Option[String], scheme: String, allowed: Vector[WebOrigin],
      tokenSet: Boolean): Verdict = origin match {
    case None => Allowed
    case Some(text) =>
      val shown = naogateway.api.Printable.text(text.take(200))
      parse(text) match {
        case None                           => Refused(s"origin '$shown' is not one")
        case Some(o) if allowed.contains(o) => Allowed
        case Some(o)                        =>
          // A WebSocket request's own scheme is ws or wss; the page it came from was fetched over http or https.
          val pageScheme = scheme.toLowerCase match {
            case "wss" | "https" => "https"
            case _               => "http"
          }
          val own = host.flatMap(ofHost(pageScheme, _))
          if (!own.contains(o)) Refused(s"origin '$shown' is not this page's")
          else if (!tokenSet && !loopbackLiteral(o.host))
            Refused(s"origin '$shown' is not loopback, and without apps.web.token only loopback pages may connect")
          else Allowed
      }
  }
}
