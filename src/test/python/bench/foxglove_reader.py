"""A Foxglove-protocol viewer of the web bench (bench.WebBench), in a process of its own as a real viewer is.

    python foxglove_reader.py ws://127.0.0.1:PORT/foxglove SECONDS

Subscribes to every channel the feed advertises (again whenever it advertises more), reads every message for SECONDS
and prints "count N" (the binary messages so far) once a second, so the bench can count those of its window. It does
not decode the messages: the viewer's own work is not the gateway's.
"""

import json
import sys
import time

from websockets.sync.client import connect

SUBPROTOCOL = "foxglove.websocket.v1"


def main(url, seconds):
    end = time.monotonic() + seconds
    subscribed = set()
    count = 0
    with connect(url, subprotocols=[SUBPROTOCOL], open_timeout=10, max_size=None) as ws:
        next_print = time.monotonic() + 1
        while time.monotonic() < end:
            try:
                frame = ws.recv(timeout=max(0.01, min(next_print, end) - time.monotonic()))
            except TimeoutError:
                frame = None
            if isinstance(frame, bytes):
                count += 1
            elif isinstance(frame, str):
                op = json.loads(frame)
                if op.get("op") == "advertise":
                    new = [c["id"] for c in op["channels"] if c["id"] not in subscribed]
                    subscribed.update(new)
                    if new:
                        ws.send(json.dumps({"op": "subscribe",
                                            "subscriptions": [{"id": c, "channelId": c} for c in new]}))
            if time.monotonic() >= next_print:
                print(f"count {count} channels {len(subscribed)}", flush=True)
                next_print += 1
    print(f"count {count} channels {len(subscribed)}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], float(sys.argv[2])))
