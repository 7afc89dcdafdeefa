"""Reads robot statuses from a running gateway's Foxglove-protocol feed (docs/web.md), as a viewer would.

    python foxglove_status.py ws://127.0.0.1:8019/foxglove ROBOT_ID [COUNT]

Subscribes to /robot/ROBOT_ID/status, decodes COUNT messages (default 3) with the schema the feed advertises (no
generated classes: the FileDescriptorSet of the advertisement alone), prints one line each, and exits 0.
"""

import base64
import json
import struct
import sys

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from websockets.sync.client import connect

SUBPROTOCOL = "foxglove.websocket.v1"
MESSAGE_DATA = 1


def message_class(channel):
    """The protobuf class of a channel, built from its advertised schema."""
    pool = descriptor_pool.DescriptorPool()
    files = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(channel["schema"]))
    for f in files.file:
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(channel["schemaName"]))


def main(url, robot_id, count):
    topic = f"/robot/{robot_id}/status"
    with connect(url, subprotocols=[SUBPROTOCOL], open_timeout=10) as ws:
        if ws.subprotocol != SUBPROTOCOL:
            print(f"the server chose subprotocol {ws.subprotocol!r}")
            return 1
        channel = None
        while channel is None:
            frame = ws.recv(timeout=30)
            if isinstance(frame, str):
                op = json.loads(frame)
                print(f"op {op['op']}")
                if op["op"] == "advertise":
                    channel = next((c for c in op["channels"] if c["topic"] == topic), None)
        print(f"channel {channel['id']} {channel['topic']} {channel['encoding']} {channel['schemaName']}")
        ws.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 1, "channelId": channel["id"]}]}))
        status = message_class(channel)
        seen = 0
        while seen < count:
            frame = ws.recv(timeout=30)
            if isinstance(frame, bytes) and frame[0] == MESSAGE_DATA:
                subscription, nanos = struct.unpack_from("<IQ", frame, 1)
                message = status.FromString(frame[13:])
                print(f"status subscription {subscription} time {nanos} role {message.activeRole} state {message.currentState}")
                seen += 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]) if len(sys.argv) > 3 else 3))
