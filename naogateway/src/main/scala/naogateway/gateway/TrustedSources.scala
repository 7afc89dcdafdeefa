package naogateway.gateway

import java.net.{InetAddress, UnknownHostException}

/** One trusted address or subnet in CIDR notation (`10.0.0.7`, `10.0.0.0/24`, `127.0.0.0/8`, IPv6 alike). */
final case class Subnet(network: InetAddress, prefixBits: Int) {
  private val net = network.getAddress

  /** Whether `address` lies in this subnet (an IPv4 subnet never contains an IPv6 address, and the reverse). */
  def contains(address: InetAddress): Boolean = {
    val a = address.getAddress
    if (a.length != net.length) false
    else {
      val full = prefixBits / 8
      val rest = prefixBits % 8
      var i = 0
      var same = true
      while (same && i < full) { same = a(i) == net(i); i += 1 }
      same && (rest == 0 || ((a(full) ^ net(full)) & (0xff << (8 - rest)) & 0xff) == 0)
    }
  }

  override def toString: String = s"${network.getHostAddress}/$prefixBits"
}

/** Parsing subnets from config. */
object Subnet {

  /** A subnet from `address[/bits]`; only literal addresses (no name lookups), with a clear error otherwise. */
  def parse(text: String): Either[String, Subnet] = {
    val trimmed = text.trim
    val (host, bits) = trimmed.indexOf('/') match {
      case -1 => trimmed -> None
      case i  => trimmed.take(i) -> Some(trimmed.drop(i + 1))
    }
    val literal = host.nonEmpty && (host.forall(c => c.isDigit || c == '.') || host.contains(':'))
    if (!literal) Left(s"'$text' is not an IP address or subnet (a literal address, optionally /prefix-bits)")
    else
      try {
        val address = InetAddress.getByName(host)
        val max = address.getAddress.length * 8
        bits.map(b => b.toIntOption.filter(n => n >= 0 && n <= max)) match {
          case Some(None)    => Left(s"'$text': the prefix must be a number from 0 to $max")
          case Some(Some(n)) => Right(Subnet(address, n))
          case None          => Right(Subnet(address, max))
        }
      } catch { case _: UnknownHostException => Left(s"'$text' is not an IP address or subnet") }
  }
}

/** Checks of trusted ranges. */
object TrustedSources {

  /** Whether `subnet` is no wider than an IPv4 `/maxPrefix` holds (an IPv6 one: the same number of addresses, a prefix
    * 96 longer); `0.0.0.0/0` and `::/0` never are.
    */
  def narrowEnough(subnet: Subnet, maxPrefix: Int): Boolean = {
    val hostBits = subnet.network.getAddress.length * 8 - subnet.prefixBits
    subnet.prefixBits > 0 && hostBits <= 32 - maxPrefix
  }
}

/** The sources whose GameController packets count; empty means any source (not allowed in competition mode). */
final case class TrustedSources(subnets: Vector[Subnet]) {

  /** Whether packets from `address` count. */
  def trusts(address: InetAddress): Boolean = subnets.isEmpty || subnets.exists(_.contains(address))

  /** Whether a source is configured at all. */
  def configured: Boolean = subnets.nonEmpty

  /** For the view and robotctl: where game state may come from. */
  def describe: String = if (subnets.isEmpty) "any source" else subnets.mkString(", ")
}
