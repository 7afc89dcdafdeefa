"""The bench's Python doors (bench.CallPathBench): the client's call to a robot and back through the ZeroMQ endpoint
(GatewayClient, --endpoint and --publish) or through the datagram door (DatagramGatewayClient, --datagram host:port).

`system.ping` on one robot, paced at one call per gap, after a warm-up; prints one JSON line with the nearest-rank
p50 and p99 in microseconds: {"p50_us": ..., "p99_us": ..., "n": ...}.
"""

from __future__ import annotations

import argparse
import json
import time
from typing import List

from naogateway_client import DatagramGatewayClient, GatewayClient


def percentile(samples: List[int], p: float) -> float:
    """Nearest-rank percentile, as the Scala bench computes it."""
    ordered = sorted(samples)
    return float(ordered[max(0, int(-(-p * len(ordered) // 1)) - 1)])


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
    samples: List[int] = []
    try:
        for i in range(args.warmup + args.samples):
            start = time.perf_counter_ns()
            client.call(args.robot, "system", "ping")
            took = time.perf_counter_ns() - start
            if i >= args.warmup:
                samples.append(took)
            rest = start + int(args.gap_ms * 1e6) - time.perf_counter_ns()
            if rest > 0:
                time.sleep(rest / 1e9)
    finally:
        client.close()
    print(json.dumps({"p50_us": percentile(samples, 0.50) / 1e3, "p99_us": percentile(samples, 0.99) / 1e3, "n": len(samples)}))


if __name__ == "__main__":
    main()
