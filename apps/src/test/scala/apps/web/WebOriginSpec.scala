package apps.web

import org.scalatest.matchers.should.Matchers
import org.scalatest.wordspec.AnyWordSpec

/** The origin rule of the web view's WebSockets, as a pure function of the handshake's headers. */
class WebOriginSpec extends AnyWordSpec with Matchers {

  private val lichtblick = WebOrigin.parse("https://app.lichtblick.example").toVector

  private def verdict(origin: Option[String], host: String = "127.0.0.1:8019",
      allowed: Vector[WebOrigin] = Vector.empty,
      token: Boolean = false) = WebOrigin.check(origin, Some(host), "http", allowed, token)

  "An origin" should {
    "read as scheme, host and port, the default port filled in, and nothing else as one" in {
      WebOrigin.parse("http://127.0.0.1:8019") shouldBe Some(WebOrigin("http", "127.0.0.1", 8019))
      WebOrigin.parse("HTTP://LocalHost") shouldBe Some(WebOrigin("http", "localhost", 80))
      WebOrigin.parse("https://app.example") shouldBe Some(WebOrigin("https", "app.example", 443))
      WebOrigin.parse("http://[::1]:8019") shouldBe Some(WebOrigin("http", "::1", 8019))
      Seq("null", "", "file://", "chrome-extension://abc", "http://a.example/path", "http://u@a.example",
        "ws://127.0.0.1:8019").foreach(o => (o, WebOrigin.parse(o)) shouldBe ((o, None)))
    }

    "be loopback only as a literal or localhost, never by asking DNS" in {
      Seq("127.0.0.1", "127.1.2.3", "localhost", "[::1]", "::1").foreach(h =>
        (h, WebOrigin.loopbackLiteral(h)) shouldBe ((h, true)))
      Seq("evil.example", "127.0.0.1.evil.example", "0.0.0.0", "192.168.1.5", "localhost.evil.example").foreach(h =>
        (h, WebOrigin.loopbackLiteral(h)) shouldBe ((h, false)))
    }
  }

  "A WebSocket handshake" should {
    "pass from the page's own origin, on 127.0.0.1 and on localhost" in {
      verdict(Some("http://127.0.0.1:8019")) shouldBe WebOrigin.Allowed
      // The server sees a WebSocket request's scheme as ws (wss): the page's was http (https).
      WebOrigin.check(Some("http://127.0.0.1:8019"), Some("127.0.0.1:8019"), "ws", Vector.empty,
        tokenSet = false) shouldBe
        WebOrigin.Allowed
      WebOrigin.check(Some("http://127.0.0.1:8019"), Some("127.0.0.1:8019"), "wss", Vector.empty,
        tokenSet = false) shouldBe a[WebOrigin.Refused]
      verdict(Some("http://localhost:8019"), host = "localhost:8019") shouldBe WebOrigin.Allowed
    }

    "pass without an Origin (a program, not a browser), on the token alone" in {
      verdict(None) shouldBe WebOrigin.Allowed
    }

    "be refused from another origin: another port, another host, another scheme, null, garbage" in {
      Seq("http://127.0.0.1:8020", "http://evil.example", "https://127.0.0.1:8019", "null", "not an origin").foreach {
        o => (o, verdict(Some(o))) should matchPattern { case (`o`, WebOrigin.Refused(_)) => }
      }
    }

    "pass from a configured origin (a Foxglove or Lichtblick web app), and only that one" in {
      verdict(Some("https://app.lichtblick.example"), allowed = lichtblick) shouldBe WebOrigin.Allowed
      verdict(Some("https://app.lichtblick.example:8443"), allowed = lichtblick) shouldBe a[WebOrigin.Refused]
    }

    "be refused without a token from a name a stranger's DNS points at this machine (rebinding), passed with one" in {
      verdict(Some("http://evil.example:8019"), host = "evil.example:8019") shouldBe a[WebOrigin.Refused]
      verdict(Some("http://gateway.team:8019"), host = "gateway.team:8019", token = true) shouldBe WebOrigin.Allowed
    }

    "name the refused origin with its control characters replaced" in {
      val WebOrigin.Refused(reason) = verdict(Some("http://evil.example\u001b[2J"))
      reason should include("\\u001b[2J")
      reason.exists(naogateway.api.Printable.control) shouldBe false
    }
  }
}
