"""The bench's floors for the Python door (bench.CallPathBench): what any request and reply between two Python
processes on loopback costs, with nothing of the gateway in it.

--transport zeromq: a pyzmq DEALER (as the client's) to a ROUTER in a second Python process that sends every message
straight back: the ZeroMQ transport alone (libzmq's I/O thread on each side, TCP on loopback).
--transport udp: a plain UDP socket to one in a second process that sends every datagram straight back.

A 40-byte body, paced at one exchange per gap after a warm-up, as zeromq_calls.py; prints one JSON line with the
nearest-rank p50 and p99 in microseconds: {"p50_us": ..., "p99_us": ..., "n": ...}.
"""

from __future__ import annotations

import argparse
import multiprocessing
import socket

import zmq
from paced import figures, paced


BODY = b"x" * 40


def zeromq_echo(address: "multiprocessing.Queue[str]") -> None:
    """A ROUTER that sends every message back until it gets b"quit"."""
    context = zmq.Context()
    router = context.socket(zmq.ROUTER)
    router.setsockopt(zmq.LINGER, 0)
    router.bind("tcp://127.0.0.1:*")
    address.put(router.getsockopt(zmq.LAST_ENDPOINT).decode())
    while True:
        frames = router.recv_multipart()
        router.send_multipart(frames)
        if frames[-1] == b"quit":
            break
    router.close()
    context.term()


def udp_echo(address: "multiprocessing.Queue[str]") -> None:
    """A UDP socket that sends every datagram back until it gets b"quit"."""
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    address.put("%s:%d" % s.getsockname())
    while True:
        data, peer = s.recvfrom(2048)
        s.sendto(data, peer)
        if data == b"quit":
            break
    s.close()


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--transport", choices=["zeromq", "udp"], required=True)
    parser.add_argument("--warmup", type=int, default=1000)
    parser.add_argument("--samples", type=int, default=2000)
    parser.add_argument("--gap-ms", type=float, default=1.0)
    args = parser.parse_args()
    address: "multiprocessing.Queue[str]" = multiprocessing.Queue()
    echo = multiprocessing.Process(target=zeromq_echo if args.transport == "zeromq" else udp_echo, args=(address,))
    echo.start()
    where = address.get(timeout=30)
    if args.transport == "zeromq":
        context = zmq.Context()
        dealer = context.socket(zmq.DEALER)
        dealer.setsockopt(zmq.LINGER, 0)
        dealer.connect(where)

        def exchange(body: bytes) -> None:
            # As GatewayClient.call: the empty delimiter, the body, then a poll and the reply.
            dealer.send_multipart([b"", body])
            if not dealer.poll(10000):
                raise RuntimeError("no echo within 10 s")
            dealer.recv_multipart()
    else:
        host, port = where.split(":")
        peer = (host, int(port))
        udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        udp.settimeout(10)

        def exchange(body: bytes) -> None:
            udp.sendto(body, peer)
            udp.recvfrom(2048)

    try:
        samples = paced(lambda: exchange(BODY), args.warmup, args.samples, args.gap_ms)
        exchange(b"quit")
    finally:
        echo.join(10)
    print(figures(samples))


if __name__ == "__main__":
    main()
