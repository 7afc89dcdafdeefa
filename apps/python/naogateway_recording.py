"""Reading the gateway's recordings (docs/recording.md) with the official mcap packages.

Each protobuf channel is decoded through the schema stored in the file itself (no generated classes needed), the
decisions channel as JSON. Usage:

    from naogateway_recording import Recording
    rec = Recording("recordings/naogateway-20260101-120000-1.mcap")
    for d in rec.datagrams():      # every datagram in and out, byte for byte
        print(d.log_time_ns, d.direction, d.source, d.destination, d.payload.hex())
    for robot_id, time_ns, status in rec.statuses():
        print(robot_id, status.activeAgent)
    for decision in rec.decisions():
        print(decision["decision"], decision)
"""

from __future__ import annotations

import json
from collections import namedtuple
from typing import Any, Dict, Iterator, Optional, Sequence, Tuple

from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

DATAGRAMS = "/gateway/datagrams"
DECISIONS = "/gateway/decisions"

# One datagram as the gateway saw it: port and direction are the RecordedPort / RecordedDirection names.
Datagram = namedtuple("Datagram", "log_time_ns port direction source destination payload robot_id")

# One decoded message of any channel.
Entry = namedtuple("Entry", "topic log_time_ns publish_time_ns value")


class Recording:
    """One recording file (or several, read one after the other in the order given)."""

    def __init__(self, *paths: str, validate_crcs: bool = True) -> None:
        self.paths = paths
        self.validate_crcs = validate_crcs

    def entries(self, topics: Optional[Sequence[str]] = None) -> Iterator[Entry]:
        """Every message of the given topics (all when None), decoded: protobuf messages, dicts (JSON) or bytes."""
        factory = DecoderFactory()
        decoders = {}
        for path in self.paths:
            with open(path, "rb") as f:
                reader = make_reader(f, validate_crcs=self.validate_crcs)
                for schema, channel, message in reader.iter_messages(topics=topics, log_time_order=False):
                    if channel.message_encoding == "json":
                        value = json.loads(message.data)
                    else:
                        key = (path, channel.id)
                        if key not in decoders:
                            decoders[key] = factory.decoder_for(channel.message_encoding, schema)
                        decode = decoders[key]
                        value = decode(message.data) if decode else bytes(message.data)
                    yield Entry(channel.topic, message.log_time, message.publish_time, value)

    def datagrams(self) -> Iterator[Datagram]:
        """Every datagram in and out, with its time, port, direction, source, destination and payload bytes."""
        for e in self.entries([DATAGRAMS]):
            d = e.value
            yield Datagram(e.log_time_ns, type(d).DESCRIPTOR.fields_by_name["port"].enum_type.values_by_number[d.port].name,
                           type(d).DESCRIPTOR.fields_by_name["direction"].enum_type.values_by_number[d.direction].name,
                           d.source, d.destination, bytes(d.payload), d.robotID if d.HasField("robotID") else None)

    def statuses(self, robot_id: Optional[int] = None) -> Iterator[Tuple[int, int, Any]]:
        """(robot id, gateway time in ns, Status) for every keep-alive; of one robot when robot_id is given."""
        for e in self.entries():
            parts = e.topic.split("/")
            if len(parts) == 4 and parts[1] == "robot" and parts[3] == "status":
                rid = int(parts[2])
                if robot_id is None or rid == robot_id:
                    yield rid, e.publish_time_ns, e.value

    def decisions(self) -> Iterator[Dict[str, Any]]:
        """The gateway's decisions, as dicts with at least "decision" and "gatewayTimeNs"."""
        for e in self.entries([DECISIONS]):
            yield e.value
