"""The bench's Python doors (bench.CallPathBench): the client's call to a robot and back through the ZeroMQ endpoint
(GatewayClient, --endpoint and --publish) or through the datagram door (DatagramGatewayClient, --datagram host:port).

`system.ping` on one robot, paced at one call per gap, after a warm-up; prints one JSON line with the nearest-rank
p50 and p99 in microseconds: {"p50_us": ..., "p99_us": ..., "n": ...}.
"""

from __future__ import annotations

import argparse

from naogateway_client import DatagramGatewayClient, GatewayClient
from paced import figures, paced



def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--endpoint")
    parser.add_argument("--publish")
    parser.add_argument("--datagram", help="host:port of the datagram door, instead of the ZeroMQ endpoint")
    parser.add_argument("--robot", type=int, default=1)
    parser.add_argument("--warmup", type=int, default=1000)
    parser.add_argument("--samples", type=int, default=2000)
    parser.add_argument("--gap-ms", type=float, default=1.0)
    args = parser.parse_args()
    if args.datagram:
        client = DatagramGatewayClient(args.datagram)
    elif args.endpoint and args.publish:
        client = GatewayClient(args.endpoint, args.publish)
    else:
        parser.error("give --datagram, or --endpoint and --publish")
    try:
        samples = paced(lambda: client.call(args.robot, "system", "ping"), args.warmup, args.samples, args.gap_ms)
    finally:
        client.close()
    print(figures(samples))


if __name__ == "__main__":
    main()
