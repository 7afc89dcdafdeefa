#!/usr/bin/env python3
"""A conformance robot for the naogateway wire protocol, written from docs/protocol.md alone.

It behaves as the thesis hardware does: the GS1500M keeps a UDP client connection for sending
(keep-alives, responses, debug data, option lists, stream segments all leave from one socket) and a
UDP server on the robot's own address, port 3838, for receiving (section 2).  Every datagram it
receives is logged with its bytes and checked against the document; every check is written as one
JSON line (section, check, pass, detail) to the report.

Compatibility mode (environment CONFORMANCE_COMPAT=1): the robot also acts on datagrams that
arrive at its sending socket.  Section 2 says nothing ever arrives there; the mode exists only so
the rest of the document can be exercised against a gateway that answers to the source port.
Datagrams arriving there are logged and reported as a section 2 failure in both modes.

Lossy mode (--loss or --loss-every): from --loss-start seconds on, the robot drops a share of the
datagrams it receives (before acting on them; a seeded random, or every n-th) and of the stream
segments it sends, as a full module buffer does (section 2: "lost and garbled datagrams are
normal").  It then checks section 7.1 (a call the gateway repeats comes as a new Request with a new
callId) and section 11 (what the gateway's stream lost is sent again).

Hostile input (--hostile-start): between its good keep-alives the robot sends frames that sections
4.3, 4.4 and 5 say a receiver refuses (gzip with a second member or bytes after it, a varint too
large for its 32-bit field, an end-group key without its start, a truncated frame) or must
tolerate (unknown groups, unknown extensions and fields, a string that is not valid UTF-8).  Each
carries a whole keep-alive whose activeAgent names the case, so whoever reads the gateway's view of
the robot can tell which ones counted.
"""

import argparse
import gzip
import json
import math
import os
import random
import select
import signal
import socket
import struct
import subprocess
import sys
import time
import zlib

MAX_DATAGRAM = 1400
# 4.1: how long a frame the robot sent may still be in flight when the gateway writes its answer.
FORM_SLACK = 1.0
OPERATION = 42
FLAG_GZIP = 2

# The catalogue of section 8, in the order of its optionPush: (name, DebuggingOptionType value).
CATALOGUE = [
    ("status.text", 1),
    ("status.table", 4),
    ("motion.plot", 3),
    ("world.field", 6),
    ("world.relative", 7),
    ("camera.image", 5),
    ("havimo.regions", 100),
    ("havimo.grid", 101),
]
CAMERA_OPTIONS = ("havimo.regions", "havimo.grid", "camera.image")
# Non-camera options go out in name order (section 8, "non-camera options").
NON_CAMERA_ORDER = sorted(n for n, _ in CATALOGUE if n not in CAMERA_OPTIONS)

# The hostile frames of --hostile-start and what the document says a receiver does with each:
# "refused" (the keep-alive it carries must not count) or "tolerated" (it counts in full).
HOSTILE_CASES = {
    "gzip-two-members": "refused",
    "gzip-trailing-zeros": "refused",
    "gzip-trailing-garbage": "refused",
    "gzip-bad-crc": "refused",
    "varint-robot-id": "refused",
    "varint-team-id": "refused",
    "end-group-without-start": "refused",
    "group-closed-by-other-field": "refused",
    "truncated-protobuf": "refused",
    "truncated-frame": "refused",
    "truncated-header": "refused",
    "oversize": "refused",
    "group": "tolerated",
    "unknown-fields": "tolerated",
    "invalid-utf8": "tolerated",
}

POSTURE_SECONDS = {"stand": 1.5, "sit": 1.0, "crouch": 0.6}
HEAD_PAN = (-2.0, 2.0)
HEAD_TILT = (-0.6, 0.5)
ARM_LIMIT = 2.5  # the document names no arm limits (7.2): this robot's own
WALK_LIMITS = (0.3, 0.3, 1.0)
# 7.1: the calls the gateway may repeat (as new Requests) when no answer came.
REPEATABLE = {"system.battery", "system.ping", "motion.getPosture", "motion.head", "motion.arms", "motion.stop", "motion.walk"}


def hexs(data):
    return " ".join("%02X" % b for b in data)


def load_classes(proto_root, gen_dir):
    """Generates the Python classes from proto/ with the official protoc (grpc_tools) and imports them."""
    files = ["naogateway/proto/%s.proto" % n for n in ("message", "rpc", "debugging", "havimo")]
    os.makedirs(gen_dir, exist_ok=True)
    if not os.path.isfile(os.path.join(gen_dir, "naogateway", "proto", "rpc_pb2.py")):
        subprocess.check_call([sys.executable, "-m", "grpc_tools.protoc", "-I", proto_root,
                               "--python_out=" + gen_dir] + files)
    sys.path.insert(0, gen_dir)
    from naogateway.proto import message_pb2, rpc_pb2, debugging_pb2, havimo_pb2  # noqa: E402
    return message_pb2, rpc_pb2, debugging_pb2, havimo_pb2


class Report:
    """The machine-readable findings: one JSON line per check result, flushed at once."""

    def __init__(self, path):
        self.out = open(path, "a", buffering=1)

    def check(self, section, check, ok, detail=""):
        self.out.write(json.dumps({"section": section, "check": check, "pass": bool(ok), "detail": detail}) + "\n")

    def close(self):
        self.out.close()


class Stream:
    """One end of the secure stream (section 11) with the thesis parameters W = 1, maxSeq 20."""

    def __init__(self, max_seq=20, rto=0.2, rto_max=2.0, idle=0.2):
        self.m = max_seq + 1
        self.max_seq = max_seq
        self.rto0, self.rto_max, self.idle_interval = rto, rto_max, idle
        self.reset()

    def reset(self):
        # 11.3: next 0, ack byte / last acknowledged / settled all maxSeq, nothing owed.
        self.next_seq = 0
        self.last = self.max_seq
        self.last_acked = self.max_seq
        self.in_flight = None  # (seq, payload, first_sent, sends)
        self.queue = []
        self.rto = self.rto0
        self.timer = None
        self.idle_owed = False
        self.last_sent = 0.0
        self.sent_data = 0
        self.pure_acks_since_data = 0
        self.unanswered = 0


class Loss:
    """The lossy link: drops a share of the datagrams received and of the stream segments sent, deterministically."""

    def __init__(self, share, seed, every, start_at):
        self.share, self.every, self.start_at = share, every, start_at
        # One generator per direction, so the drops of one direction do not depend on the traffic of the other.
        self.rng = {"in": random.Random(seed), "out": random.Random(seed + 1)}
        self.seen = {"in": 0, "out": 0}
        self.dropped = {"in": 0, "out": 0}
        self.announced = False

    def enabled(self):
        return self.share > 0 or self.every > 0

    def active(self, now):
        return self.enabled() and now >= self.start_at

    def drop(self, direction, now):
        """Whether this datagram (direction "in": received, "out": a stream segment sent) is lost."""
        if not self.active(now):
            return False
        self.seen[direction] += 1
        if self.every > 0:
            lost = self.seen[direction] % self.every == 0
        else:
            lost = self.rng[direction].random() < self.share
        if lost:
            self.dropped[direction] += 1
        return lost


def varint(n):
    """Section 5: 7 bits per byte, least significant group first, top bit = more follows (n >= 0)."""
    out = bytearray()
    while True:
        b = n & 0x7F
        n >>= 7
        if n:
            out.append(b | 0x80)
        else:
            out.append(b)
            return bytes(out)


def key(field, wire_type):
    return varint((field << 3) | wire_type)


def length_delimited(field, data):
    return key(field, 2) + varint(len(data)) + data


class Robot:
    """The robot's state machine: keep-alive, RPC contract, debug options, GameController, stream, restart."""

    def __init__(self, args, classes):
        self.args = args
        self.pb_msg, self.pb_rpc, self.pb_dbg, self.pb_hav = classes
        self.compat = os.environ.get("CONFORMANCE_COMPAT", "") == "1"
        self.report = Report(args.report)
        self.log = open(args.log, "a", buffering=1)
        gh, gp = args.gateway.rsplit(":", 1)
        self.gateway = (gh, int(gp))
        # The module's client connection: sends everything, bound to an ephemeral port of the robot's address.
        self.send_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.send_sock.bind((args.address, 0))
        # The module's UDP server on 3838 (section 2).
        self.recv_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.recv_sock.bind((args.address, args.port))
        self.stream = Stream()
        self.boot_id = args.boot_id
        self.call_ids = {}
        self.stop_flag = False
        self.keepalive_forms = args.forms.split(",")
        self.keepalive_count = 0
        self.silent_until = 0.0
        self.pending_restart = None
        self.counts = {"on3838": 0, "onsend": 0, "requests": 0, "gc": 0, "segments": 0,
                       "stream_resends": 0, "stream_duplicates_received": 0, "requests_dropped": 0,
                       "retries_seen": 0, "data_segments_dropped": 0, "data_segments_sent_again": 0}
        # Lossy mode: its start is set when the run starts.
        self.loss = Loss(args.loss, args.loss_seed, args.loss_every, float("inf"))
        # Requests this robot dropped, by (module, method, parameters): (time, callId), to recognise a repeated call (7.1).
        self.dropped_requests = {}
        # Gateway data segments this robot dropped and has not seen again yet: [time, seq, payload].
        self.dropped_segments = []
        # Robot -> gateway stream payloads offered, by the uptimeMs each carries (the harness compares what arrived).
        self.stream_offered = []
        self.unanswered_limit = 12 if self.loss.enabled() else 6
        self.hostile_cases = []
        self.hostile_at = float("inf")
        self.next_hostile = None
        self.first_session = True
        # Requests other than probes in this session (7.2), and the forms of the frames sent lately (4.1).
        self.session_requests = 0
        self.sent_forms = []
        self.active_before_restart = None
        self.reenabled_after_restart = None
        self.restarts = 0
        self.boot()
        self.report.check("2", "robot-listens-on-3838", True,
                          "sending from %s:%d, receiving on %s:%d%s" % (
                              args.address, self.send_sock.getsockname()[1], args.address, args.port,
                              " (compatibility mode: also acting on the sending socket)" if self.compat else ""))

    # ----- session -------------------------------------------------------------------------------------------

    def boot(self):
        """Power-up: what 7.2 (system.reset) says a restart does, and the start state of a fresh robot."""
        now = time.monotonic()
        self.boot_time = now
        self.posture = "sit"
        self.motion_end = None  # (time, target, reply-context)
        self.walk = (0.0, 0.0, 0.0)
        self.lease_until = None
        self.head = (0.0, 0.0)
        self.arms = (0.0, 0.0, 0.0, 0.0)
        self.battery = self.args.battery
        self.enabled = set()
        self.stream.reset()
        self.next_keepalive = now
        self.next_debug = now
        self.next_camera = now
        self.camera_frame = 0
        # Section 8 bookkeeping for this session.
        self.seen_debug_command = False
        self.pushed = False
        self.stream_sends_left = self.args.stream_sends
        self.next_stream_send = now + self.args.stream_start
        self.dropped_segments = []

    def uptime_ms(self):
        return int((time.monotonic() - self.boot_time) * 1000) & 0xFFFFFFFF

    # ----- framing (section 4) -------------------------------------------------------------------------------

    def frame(self, message, form="legacy", gz=False):
        payload = message.SerializeToString()
        flags = 0
        if gz:
            payload = gzip.compress(payload, mtime=0)
            flags = FLAG_GZIP
        if form == "legacy":
            header = struct.pack(">HBBII", OPERATION, flags, 0, 0, len(payload))
        else:
            header = struct.pack(">HBBI", OPERATION, flags, 0, len(payload))
        data = header + payload
        if len(data) > MAX_DATAGRAM:
            raise ValueError("frame of %d bytes over the 1400-byte limit" % len(data))
        return data

    def parse_frame(self, data):
        """Section 4.2 / 4.4: returns (form, flags, Message) or raises ValueError naming the refusal."""
        if len(data) > MAX_DATAGRAM:
            raise ValueError("Oversize(%d)" % len(data))
        if len(data) < 8:
            raise ValueError("Truncated(8, %d)" % len(data))
        op, flags, align, word = struct.unpack(">HBBI", data[:8])
        if op != OPERATION or align != 0:
            raise ValueError("WrongOperation(%d, %d)" % (op, align))
        if flags & ~FLAG_GZIP:
            raise ValueError("UnsupportedFlags(%d)" % flags)
        if word == 0:
            if len(data) < 12:
                raise ValueError("Truncated(12, %d)" % len(data))
            form, length, start = "legacy", struct.unpack(">I", data[8:12])[0], 12
        else:
            form, length, start = "compact", word, 8
        if length != len(data) - start:
            raise ValueError("LengthMismatch(%d, %d)" % (length, len(data) - start))
        payload = data[start:]
        if flags & FLAG_GZIP:
            d = zlib.decompressobj(16 + zlib.MAX_WBITS)
            try:
                inflated = d.decompress(payload, 65536 + 1)
            except zlib.error as e:
                raise ValueError("BadGzip(%s)" % e)
            if not d.eof or d.unused_data or d.unconsumed_tail or len(inflated) > 65536:
                raise ValueError("BadGzip(not exactly one member)")
            payload = inflated
        msg = self.pb_msg.Message()
        try:
            msg.ParseFromString(payload)
        except Exception as e:  # the library's DecodeError, and a missing required robotID
            raise ValueError("BadProtobuf(%s)" % e)
        if not msg.IsInitialized():
            raise ValueError("BadProtobuf(required field missing)")
        return form, flags, msg

    # ----- sending -------------------------------------------------------------------------------------------

    def send_raw(self, data):
        if data[:2] == b"\x00\x2a" and len(data) >= 8:
            # 4.1: the gateway answers in the header form of the robot's latest frame.
            now = time.monotonic()
            self.sent_forms.append((now, "legacy" if data[4:8] == b"\x00\x00\x00\x00" else "compact"))
            self.sent_forms = [f for f in self.sent_forms[:-1] if f[0] > now - FORM_SLACK] + self.sent_forms[-1:]
        self.send_sock.sendto(data, self.gateway)

    def send_message(self, message, form="legacy", via_stream=False):
        data = self.frame(message, form)
        if via_stream:
            self.stream_offer(data)
        else:
            self.send_raw(data)

    def message(self):
        m = self.pb_msg.Message()
        m.robotID = self.args.robot_id
        return m

    def keepalive(self):
        form = self.keepalive_forms[self.keepalive_count % len(self.keepalive_forms)]
        self.keepalive_count += 1
        # The header form rides in the agent's name, so whoever reads the published status can tell
        # which forms the gateway accepted (4.1, 4.3).
        m = self.keepalive_message("conformance-" + form)
        header, gz = (form.split("-") + [""])[:2]
        data = self.frame(m, header, gz == "gzip")
        self.send_raw(data)

    def keepalive_message(self, agent):
        """One keep-alive (6.2): Status and RobotHealth, every field set, activeAgent = agent."""
        m = self.message()
        st = m.Extensions[self.pb_msg.status]
        up = self.uptime_ms()
        st.timestamp = up
        st.teamID = self.args.team
        st.timeOnline = up // 1000
        st.robotPosition.x = -1000
        st.robotPosition.y = 0
        st.robotPosition.rotation = 0.0
        st.activeAgent = agent
        st.activeRole = "striker"
        st.currentState = self.posture
        h = m.Extensions[self.pb_msg.robotHealth]
        h.batteryVoltage = self.battery
        h.posture = self.posture
        h.uptimeMs = up
        h.bootId = self.boot_id
        return m

    # ----- hostile input (sections 4.3, 4.4, 5) -----------------------------------------------------------------

    def hostile_frame(self, case):
        """A keep-alive whose activeAgent is "hostile-<case>", framed or encoded as `case` says (HOSTILE_CASES)."""
        m = self.keepalive_message("hostile-" + case)
        st, h = m.Extensions[self.pb_msg.status], m.Extensions[self.pb_msg.robotHealth]
        status_b, health_b = st.SerializeToString(), h.SerializeToString()
        robot_id = key(1, 0) + varint(self.args.robot_id)

        def body(rid=robot_id, status=status_b, health=health_b, extra=b""):
            # Ascending field numbers: robotID (1), status (23), robotHealth (7105), then whatever is added.
            return rid + length_delimited(23, status) + length_delimited(7105, health) + extra

        def legacy(payload, flags=0):
            return struct.pack(">HBBII", OPERATION, flags, 0, 0, len(payload)) + payload

        def status_without(field):
            copy = self.pb_msg.Status()
            copy.CopyFrom(st)
            copy.ClearField(field)
            return copy.SerializeToString()

        plain = body()
        member = gzip.compress(plain, mtime=0)
        if case == "gzip-two-members":  # 4.3: exactly one member; a concatenating reader would find the keep-alive
            return legacy(member + gzip.compress(b"", mtime=0), FLAG_GZIP)
        if case == "gzip-trailing-zeros":  # 4.3: nothing after the member's 8-byte trailer
            return legacy(member + bytes(4), FLAG_GZIP)
        if case == "gzip-trailing-garbage":
            return legacy(member + b"JUNK", FLAG_GZIP)
        if case == "gzip-bad-crc":  # 4.3: a member whose CRC-32 does not match
            bad = bytearray(member)
            bad[-8] ^= 0xFF
            return legacy(bytes(bad), FLAG_GZIP)
        if case == "varint-robot-id":  # 5: robotID 2^32 + id does not fit an int32: refused, never read as id
            return legacy(body(rid=key(1, 0) + varint(2 ** 32 + self.args.robot_id)))
        if case == "varint-team-id":  # 5: teamID (uint32) 2^32 + team: refused
            return legacy(body(status=status_without("teamID") + key(2, 0) + varint(2 ** 32 + self.args.team)))
        if case == "end-group-without-start":  # 5: malformed, refused
            return legacy(body(extra=key(50, 4)))
        if case == "group-closed-by-other-field":  # 5: an end-group key that closes another field's group
            return legacy(body(extra=key(50, 3) + key(1, 0) + varint(7) + key(51, 4)))
        if case == "truncated-protobuf":  # 4.4 BadProtobuf: robotHealth cut short; the Status before it is whole
            return legacy(plain[:-2])
        if case == "truncated-frame":  # 4.4 LengthMismatch: the datagram ends before the declared length
            return legacy(plain)[:-5]
        if case == "truncated-header":  # 4.4 Truncated(8, 7)
            return legacy(plain)[:7]
        if case == "oversize":  # 4.4 Oversize: 1401 bytes, padded with an unknown field
            pad = 1401 - len(legacy(plain)) - 4
            return legacy(body(extra=length_delimited(90, bytes(pad))))[:1401]
        if case == "group":  # 5: unknown groups skipped at every depth: top level, nested, inside Status
            group = key(50, 3) + key(1, 0) + varint(7) + length_delimited(2, b"x") + key(51, 3) + key(1, 5) + bytes(4) \
                + key(51, 4) + key(50, 4)
            return legacy(body(status=status_b + key(30, 3) + key(1, 0) + varint(1) + key(30, 4), extra=group))
        if case == "unknown-fields":  # 5: an unknown extension and unknown fields of wire types 0, 1, 2, 5
            extra = length_delimited(7150, key(1, 0) + varint(1) + length_delimited(2, b"abc")) + key(99, 1) + bytes(8) \
                + key(98, 5) + bytes(4)
            status = status_b + key(40, 0) + varint(300) + key(41, 1) + bytes(8) + key(42, 5) + bytes(4) \
                + length_delimited(43, b"zz")
            return legacy(body(status=status, health=health_b + key(20, 0) + varint(1), extra=extra))
        if case == "invalid-utf8":  # 5: each malformed byte sequence reads as U+FFFD, the rest counts
            agent = b"hostile-invalid-utf8-\xff\xfe-end"
            return legacy(body(status=status_without("activeAgent") + length_delimited(12, agent)))
        raise ValueError(case)

    def send_hostile(self, now):
        case = self.hostile_cases.pop(0)
        data = self.hostile_frame(case)
        self.send_raw(data)
        section = "4.3" if case.startswith("gzip") else "4.4" if case.startswith(("truncated", "oversize")) else "5"
        self.report.check(section, "hostile-frame-sent", True, "%s (%s): %s" % (case, HOSTILE_CASES[case], hexs(data)))
        if not self.hostile_cases:
            print("hostile done", flush=True)

    def answer(self, request, form, via_stream, value=None, error=None):
        m = self.message()
        r = m.Extensions[self.pb_rpc.rpcResponse]
        if error is not None:
            r.error = error
        else:
            kind, v = value
            if kind == "bool":
                r.returnval.bool = v
            elif kind == "float":
                r.returnval.float = v
            elif kind == "int":
                r.returnval.int = v
            else:
                r.returnval.string = v
        if request.HasField("callId"):
            r.callId = request.callId
        # 7.1: the same header form, the same transport, never gzip.
        self.send_message(m, form, via_stream)

    def push_options(self, form, via_stream):
        m = self.message()
        lst = m.Extensions[self.pb_dbg.debuggingCommands].optionPush
        for name, typ in CATALOGUE:
            o = lst.options.add()
            o.name = name
            o.type = typ
            o.enabled = name in self.enabled
        self.send_message(m, form, via_stream)
        self.pushed = True

    # ----- RPC (section 7) ------------------------------------------------------------------------------------

    def floats(self, request, count):
        params = list(request.params)
        if len(params) != count or any(not p.HasField("float") for p in params):
            raise BadParams("expected %d numbers, got %d parameter(s)" % (count, len(params)))
        values = [p.float for p in params]
        if any(not math.isfinite(v) for v in values):
            raise BadParams("not finite: %s" % values)
        return values

    def serve(self, request, form, via_stream, raw):
        name = "%s.%s" % (request.module, request.method)
        self.counts["requests"] += 1
        now = time.monotonic()
        self.note_call_id(request, name, raw, now)
        # 7.1: a call the gateway repeats because this robot dropped it comes as a new Request with a new callId.
        earlier = self.dropped_requests.pop(self.call_key(request), None)
        if earlier is not None and now - earlier[0] < 5.0:
            self.counts["retries_seen"] += 1
            new_id = request.HasField("callId") and request.callId != earlier[1]
            self.report.check("7.1", "repeated-call-has-new-call-id", new_id,
                              "%s dropped with callId %s, arrived again %.3f s later with callId %s; bytes %s" % (
                                  name, earlier[1], now - earlier[0], request.callId if request.HasField("callId") else None, hexs(raw)))
            if name not in REPEATABLE and name != "heartbeat.probe":
                self.report.check("7.1", "only-repeatable-calls-repeated", False,
                                  "%s arrived again %.3f s after a dropped copy; 7.1 repeats only %s" % (name, now - earlier[0], sorted(REPEATABLE)))
        if name != "heartbeat.probe" and self.session_requests == 0:
            # 7.2: no motion.stop at first contact (it would overtake an application's first command); after a
            # restart's silence, which takes the robot offline, the motion.stop comes first.
            if self.first_session:
                self.report.check("7.2", "no-motion-stop-at-first-contact", name != "motion.stop",
                                  "first request other than the probe at first contact: %s" % name)
            else:
                self.report.check("7.2", "motion-stop-first-when-back-online", name == "motion.stop",
                                  "first request other than the probe after restart %d: %s" % (self.restarts, name))
        if name != "heartbeat.probe":
            self.session_requests += 1
        try:
            result = self.dispatch(request, name, form, via_stream)
        except BadParams as e:
            self.answer(request, form, via_stream, error="bad parameters: %s" % e)
            return
        except RobotError as e:
            self.answer(request, form, via_stream, error=str(e))
            return
        if result is not None:
            self.answer(request, form, via_stream, value=result)

    def note_call_id(self, request, name, raw, now, dropped=False):
        """7.1: a callId is never sent twice (a dropped copy counts as sent)."""
        if request.HasField("callId"):
            cid = request.callId
            if cid in self.call_ids:
                t, earlier = self.call_ids[cid]
                self.report.check("7.1", "call-id-never-repeated", False,
                                  "callId %d (%s) arrived again %.3f s after %s; bytes %s" % (cid, name, now - t, earlier, hexs(raw)))
            else:
                self.report.check("7.1", "call-id-never-repeated", True, "callId %d %s%s" % (cid, name, " (dropped)" if dropped else ""))
            self.call_ids[cid] = (now, name + (" (dropped)" if dropped else ""))
        else:
            self.report.check("6.6", "request-carries-call-id", False, "%s without callId; bytes %s" % (name, hexs(raw)))

    @staticmethod
    def call_key(request):
        return request.module, request.method, tuple(p.SerializeToString() for p in request.params)

    def dispatch(self, request, name, form, via_stream):
        now = time.monotonic()
        if name == "motion.walk":
            vx, vy, om = self.floats(request, 3)
            if self.posture not in ("stand", "walking"):
                raise RobotError("not standing: %s" % self.posture)
            lx, ly, lo = WALK_LIMITS
            self.walk = (max(-lx, min(lx, vx)), max(-ly, min(ly, vy)), max(-lo, min(lo, om)))
            self.posture = "walking"
            self.lease_until = now + 0.5
            return ("bool", True)
        if name == "motion.stop":
            self.floats(request, 0)
            self.end_walk()
            return ("bool", True)
        if name == "motion.head":
            pan, tilt = self.floats(request, 2)
            if not (HEAD_PAN[0] <= pan <= HEAD_PAN[1]) or not (HEAD_TILT[0] <= tilt <= HEAD_TILT[1]):
                raise RobotError("out of range: pan %.3f (±2.0), tilt %.3f (-0.6..0.5)" % (pan, tilt))
            self.head = (pan, tilt)
            return ("bool", True)
        if name == "motion.arms":
            values = self.floats(request, 4)
            self.arms = tuple(max(-ARM_LIMIT, min(ARM_LIMIT, v)) for v in values)
            return ("bool", True)
        if name == "motion.posture":
            params = list(request.params)
            if len(params) != 1 or not params[0].HasField("string"):
                raise BadParams("expected one posture name, got %d parameter(s)" % len(params))
            target = params[0].string
            if target not in POSTURE_SECONDS:
                raise BadParams("unknown posture %r" % target)
            if self.posture == "moving":
                raise RobotError("busy: moving")
            if self.posture == target:
                return ("string", target)
            self.end_walk()
            self.posture = "moving"
            self.battery -= 0.002
            self.motion_end = (now + POSTURE_SECONDS[target], target, request, form, via_stream)
            return None  # answered when the motion has ended
        if name == "motion.getPosture":
            self.floats(request, 0)
            return ("string", self.posture)
        if name == "speech.say":
            params = list(request.params)
            if len(params) != 1 or not params[0].HasField("string"):
                raise BadParams("expected one text, got %d parameter(s)" % len(params))
            return ("bool", True)
        if name == "system.battery":
            self.floats(request, 0)
            return ("float", self.battery)
        if name == "system.ping":
            self.floats(request, 0)
            return ("int", self.uptime_ms())
        if name == "system.reset":
            self.floats(request, 0)
            # Sends the answer, then restarts (7.2).
            self.pending_restart = True
            return ("bool", True)
        raise RobotError("unknown method: %s" % name)

    def end_walk(self):
        if self.posture == "walking":
            self.posture = "stand"
        self.walk = (0.0, 0.0, 0.0)
        self.lease_until = None

    def restart(self):
        self.restarts += 1
        self.active_before_restart = set(self.enabled)
        self.reenabled_after_restart = None
        self.boot_id += 1
        self.first_session = False
        self.session_requests = 0
        self.boot()
        # The module's start-up: nothing is received or sent for about 4 s (7.2, 12).
        self.silent_until = time.monotonic() + self.args.restart_silence
        self.report.check("7.2", "restart", True, "system.reset: bootId now %d, silent %.1f s" % (self.boot_id, self.args.restart_silence))

    # ----- debug options (section 8) --------------------------------------------------------------------------

    def debug_command(self, cmd, form, via_stream, raw):
        fields = [f for f in ("optionPull", "optionPush", "optionEnable", "optionDisable") if cmd.HasField(f)]
        self.report.check("6.3", "exactly-one-field", len(fields) == 1, "fields %s; bytes %s" % (fields, hexs(raw)))
        if not fields:
            return
        kind = fields[0]
        if not self.seen_debug_command:
            self.seen_debug_command = True
            self.report.check("8", "first-command-is-option-pull", kind == "optionPull",
                              "first debug command of boot %d: %s; bytes %s" % (self.boot_id, kind, hexs(raw)))
        if kind == "optionPush":
            self.report.check("6.3", "gateway-never-sends-option-push", False, hexs(raw))
            return
        if kind == "optionPull":
            self.push_options(form, via_stream)
            return
        names = list(getattr(cmd, kind).options)
        if kind == "optionEnable":
            self.report.check("8", "no-enable-before-push", self.pushed,
                              "optionEnable %s before this session's optionPush" % names if not self.pushed else str(names))
            known = [n for n, _ in CATALOGUE]
            unmatched = [x for x in names if not any(k == x or k.startswith(x + ".") for k in known)]
            self.report.check("8", "enable-names-match-pushed-list", not unmatched, "names %s, unmatched %s" % (names, unmatched))
        for x in names:
            for n, _ in CATALOGUE:
                if n == x or n.startswith(x + "."):
                    if kind == "optionEnable":
                        self.enabled.add(n)
                    else:
                        self.enabled.discard(n)
        if kind == "optionEnable" and self.active_before_restart and self.reenabled_after_restart is None:
            if self.active_before_restart <= self.enabled:
                self.reenabled_after_restart = True
                self.report.check("8", "re-enabled-after-restart", True, "options %s" % sorted(self.enabled))
        # This project's robot answers enable / disable with the updated list (8, step 5).
        self.push_options(form, via_stream)

    def debug_output(self, now):
        if now >= self.next_debug:
            self.next_debug = now + 0.1
            up = self.uptime_ms()
            for name in NON_CAMERA_ORDER:
                if name in self.enabled:
                    self.send_raw(self.frame(self.debug_data(name, up)))
        if now >= self.next_camera:
            self.next_camera = now + 0.06
            wanted = [n for n in CAMERA_OPTIONS if n in self.enabled]
            if wanted:
                self.camera_frame += 1
                up = self.uptime_ms()
                for name in wanted:
                    self.send_raw(self.frame(self.camera_data(name, up)))

    def debug_data(self, name, up):
        m = self.message()
        d = m.Extensions[self.pb_dbg.debugData]
        d.option = name
        d.timestamp = up
        if name == "status.text":
            d.text.text = "posture %s, battery %.2f V" % (self.posture, self.battery)
        elif name == "status.table":
            for k, v in (("battery", "%.2f" % self.battery), ("posture", self.posture), ("uptime", "%d ms" % up)):
                row = d.table.rows.add()
                row.key, row.value = k, v
        elif name == "motion.plot":
            for series, v in zip(("vx", "vy", "omega"), self.walk):
                s = d.plot.samples.add()
                s.series, s.value = series, v
        elif name == "world.field":
            for label, x, r in (("robot", -1000, 150), ("ball", 0, 50)):
                s = d.fieldDrawing.shapes.add()
                s.kind, s.x1, s.y1, s.radius, s.label = 3, x, 0, r, label
        elif name == "world.relative":
            o = d.relativePosition.objects.add()
            o.name, o.distance, o.angle = "ball", 1000, 0.0
        return m

    def camera_data(self, name, up):
        m = self.message()
        record = struct.pack("<BBHIIBBBB", 1, 1, 50, 4000, 3000, 84, 76, 64, 56)
        if name == "havimo.regions":
            r = m.Extensions[self.pb_hav.havimoRegions]
            r.frame, r.timestamp, r.records = self.camera_frame, up, record
        elif name == "havimo.grid":
            g = m.Extensions[self.pb_hav.havimoGrid]
            g.frame, g.timestamp, g.cells = self.camera_frame, up, bytes(768)
        else:
            d = m.Extensions[self.pb_dbg.debugData]
            d.option, d.timestamp = name, up
            d.image.width, d.image.height, d.image.format, d.image.pixels = 32, 24, 3, bytes(768)
            s = d.image.overlay.add()
            s.kind, s.x1, s.y1, s.x2, s.y2, s.label = 2, 76, 56, 84, 64, "colour 1"
        return m

    # ----- GameController (section 10) ------------------------------------------------------------------------

    def game_controller(self, data, source):
        self.counts["gc"] += 1
        head = data[:4]
        if head != b"RGme":
            self.report.check("10", "robot-receives-only-RGme", False, "%s from %s" % (hexs(data[:8]), source))
            return
        if len(data) == 158 and data[4] == 8:
            teams = [(18 + 70 * i, data[18 + 70 * i]) for i in (0, 1)]
            own = [off for off, number in teams if number == self.args.team]
            if not own:
                return
            answer = b"RGrt" + bytes([2, self.args.team, self.args.player, 2])
            self.send_sock.sendto(answer, (source[0], 3838))
            self.report.check("10.3", "answered-v8-control-packet", True,
                              "packet %d from %s answered with %s" % (data[5], source[0], hexs(answer)))
        elif len(data) == 116 and struct.unpack("<I", data[4:8])[0] == 7:
            self.report.check("10.3", "version-7-ignored", True, "from %s" % (source,))
        else:
            self.report.check("10", "control-packet-size-and-version", False, "%d bytes, %s" % (len(data), hexs(data[:8])))

    # ----- secure stream (section 11) -------------------------------------------------------------------------

    def stream_offer(self, payload):
        self.stream.queue.append(payload)
        self.stream_pump(time.monotonic())

    def stream_pump(self, now):
        s = self.stream
        if s.in_flight is None and s.queue:
            payload = s.queue.pop(0)
            seq = s.next_seq
            s.next_seq = (s.next_seq + 1) % s.m
            s.in_flight = [seq, payload, now, 1]
            self.send_segment(bytes([seq, s.last]) + payload, now)
            s.sent_data += 1
            s.pure_acks_since_data = 0
            s.timer = now + s.rto
        elif s.in_flight is not None and s.timer is not None and now >= s.timer:
            seq, payload, first, sends = s.in_flight
            s.in_flight[3] = sends + 1
            s.rto = min(s.rto * 2, s.rto_max)
            s.timer = now + s.rto
            self.send_segment(bytes([seq, s.last]) + payload, now)
            s.pure_acks_since_data = 0
            self.counts["stream_resends"] += 1
            if sends + 1 == self.unanswered_limit:
                self.report.check("11.4", "data-segments-answered", False,
                                  "seq %d sent %d times over %.1f s without an ACK" % (seq, sends + 1, now - first))
        if s.idle_owed and s.in_flight is None and now - s.last_sent >= s.idle_interval:
            s.idle_owed = False
            self.send_segment(bytes([self.settled(), s.last]), now)

    def settled(self):
        return self.stream.last_acked

    def send_segment(self, data, now):
        self.stream.last_sent = now
        if self.loss.drop("out", now):
            self.log.write(json.dumps({"t": round(now - self.start, 3), "at": "sent", "boot": self.boot_id,
                                       "dropped": True, "bytes": hexs(data)}) + "\n")
            return
        self.send_raw(data)

    def segment(self, data, raw_ok, where):
        s = self.stream
        now = time.monotonic()
        self.counts["segments"] += 1
        seq, ack = data[0], data[1]
        ok = seq <= s.max_seq and ack <= s.max_seq
        self.report.check("11.1", "seq-and-ack-within-maxseq", ok, "%s (maxSeq %d)" % (hexs(data[:2]), s.max_seq))
        if not ok:
            return
        # The ack byte (11.5).
        if s.in_flight is not None and ack == s.in_flight[0]:
            s.last_acked = ack
            s.in_flight = None
            s.timer = None
            s.rto = s.rto0
        if len(data) == 2:
            s.pure_acks_since_data += 1
            if s.sent_data == 0:
                self.report.check("11.3", "fresh-endpoint-gets-no-segment", False,
                                  "pure ACK %s to a robot that has sent no stream data since boot %d" % (hexs(data), self.boot_id))
            elif s.pure_acks_since_data > 2:
                self.report.check("11.4", "idle-ack-sent-once", False,
                                  "pure ACK %s is the %d-th since the robot's last data segment" % (hexs(data), s.pure_acks_since_data))
            # A skip notice: byte 0 exactly the next expected number (11.7).
            if seq == (s.last + 1) % s.m:
                s.last = seq
                self.send_segment(bytes([self.settled(), s.last]), now)
            self.stream_pump(now)
            return
        d = (seq - (s.last + 1)) % s.m
        if d == 0:
            s.last = seq
            self.send_segment(bytes([self.settled(), s.last]), now)
            s.idle_owed = True
            self.report.check("11.4", "data-segment-in-order", True, "seq %d, %d payload bytes" % (seq, len(data) - 2))
            self.datagram(data[2:], where, via_stream=True)
        elif d >= s.m - 1:
            self.counts["stream_duplicates_received"] += 1
            self.send_segment(bytes([self.settled(), s.last]), now)
        else:
            self.report.check("11.4", "data-segment-in-range", False, "seq %d while expecting %d" % (seq, (s.last + 1) % s.m))
        self.stream_pump(now)

    # ----- receiving ------------------------------------------------------------------------------------------

    def received(self, data, source, where):
        now = time.monotonic()
        self.log.write(json.dumps({"t": round(now - self.start, 3), "at": where, "from": "%s:%d" % source,
                                   "boot": self.boot_id, "bytes": hexs(data)}) + "\n")
        self.counts["on3838" if where == "3838" else "onsend"] += 1
        if where == "send":
            self.report.check("2", "gateway-sends-to-port-3838", False,
                              "datagram from %s:%d arrived at the robot's sending port %d, not 3838: %s" % (
                                  source[0], source[1], self.send_sock.getsockname()[1], hexs(data[:48])))
            if not self.compat:
                return
        else:
            if source[1] != 3838 or data[:2] != b"RG":
                self.report.check("2", "gateway-sends-to-port-3838", True, "from %s:%d: %s" % (source[0], source[1], hexs(data[:24])))
        if now < self.silent_until:
            return  # the module is still starting up
        if len(data) < 2 or len(data) > MAX_DATAGRAM:
            self.report.check("3", "datagram-size", False, "%d bytes" % len(data))
            return
        if data[:2] == b"RG":
            self.game_controller(data, source)
        elif data[0] < 42 and data[1] < 42:
            self.segment(data, True, where)
        else:
            self.datagram(data, where, via_stream=False)

    def datagram(self, data, where, via_stream):
        """One FU-Remote frame, plain or the payload of the stream."""
        if data[:2] != b"\x00\x2a":
            self.report.check("3", "known-datagram-kind", False, hexs(data[:16]))
            return
        try:
            form, flags, msg = self.parse_frame(data)
        except ValueError as e:
            self.report.check("4.4", "frame-valid", False, "%s: %s" % (e, hexs(data)))
            return
        if not via_stream:
            # 4.1: the form of the robot's latest frame (legacy before any). A frame the gateway wrote just before
            # the robot's latest one arrived is in flight, so the forms of the last FORM_SLACK seconds count too.
            allowed = set(f for _, f in self.sent_forms) or {"legacy"}
            self.report.check("4.1", "gateway-sends-form-of-latest-frame", form in allowed,
                              "%s form; the robot's latest frames: %s; bytes %s" % (form, sorted(allowed), hexs(data[:12])))
        self.report.check("6.1", "robot-id-is-addressed-robot", msg.robotID == self.args.robot_id,
                          "robotID %d" % msg.robotID)
        handled = False
        if msg.HasExtension(self.pb_rpc.rpcRequest):
            handled = True
            self.serve(msg.Extensions[self.pb_rpc.rpcRequest], form, via_stream, data)
        if msg.HasExtension(self.pb_dbg.debuggingCommands):
            handled = True
            self.debug_command(msg.Extensions[self.pb_dbg.debuggingCommands], form, via_stream, data)
        if msg.HasExtension(self.pb_rpc.rpcResponse) or msg.HasExtension(self.pb_msg.status):
            self.report.check("6.1", "gateway-sends-only-requests-and-commands", False, hexs(data))
        if not handled:
            self.report.check("6.1", "frame-carries-a-request-or-command", False, "nothing this robot serves: " + hexs(data))

    # ----- the lossy link -------------------------------------------------------------------------------------

    def lost(self, data, source, where):
        """A received datagram the lossy link drops: logged, never acted on. Only its callId and, for a new stream
        data segment, its sequence number and payload are noted, to check that the gateway repeats them (7.1, 11.5)."""
        now = time.monotonic()
        self.log.write(json.dumps({"t": round(now - self.start, 3), "at": where, "from": "%s:%d" % source,
                                   "boot": self.boot_id, "dropped": True, "bytes": hexs(data)}) + "\n")
        if now < self.silent_until or len(data) < 2:
            return
        s = self.stream
        if len(data) > 2 and data[0] < 42 and data[1] < 42:
            if data[0] == (s.last + 1) % s.m:  # new data: the gateway must send it again
                self.counts["data_segments_dropped"] += 1
                self.dropped_segments.append((now, data[0], bytes(data[2:])))
        elif data[:2] == b"\x00\x2a":
            try:
                _, _, msg = self.parse_frame(data)
            except ValueError:
                return
            if msg.HasExtension(self.pb_rpc.rpcRequest):
                request = msg.Extensions[self.pb_rpc.rpcRequest]
                self.counts["requests_dropped"] += 1
                self.note_call_id(request, "%s.%s" % (request.module, request.method), data, now, dropped=True)
                self.dropped_requests[self.call_key(request)] = (now, request.callId if request.HasField("callId") else None)

    def first_data_segment(self, data, now):
        """Whether `data` is the first new stream data segment of the lossy link, which it always loses: the seeded drops
        hit one of the gateway's dozen or so data segments in most runs but not all, and 11.5's repair is checked in
        every run."""
        if not self.loss.active(now) or self.counts["data_segments_dropped"] > 0 or now < self.silent_until:
            return False
        s = self.stream
        return len(data) > 2 and data[0] < 42 and data[1] < 42 and data[0] == (s.last + 1) % s.m

    def data_segment_again(self, data):
        """A stream data segment that repeats one the lossy link dropped: the gateway sent it again (11.5)."""
        if self.dropped_segments and len(data) > 2 and data[0] < 42 and data[1] < 42:
            again = [e for e in self.dropped_segments if e[1] == data[0] and e[2] == bytes(data[2:])]
            for e in again:
                self.dropped_segments.remove(e)
                self.counts["data_segments_sent_again"] += 1

    # ----- main loop ------------------------------------------------------------------------------------------

    def tick(self, now):
        if now < self.silent_until:
            return
        if self.lease_until is not None and now >= self.lease_until:
            self.end_walk()
        if self.motion_end is not None and now >= self.motion_end[0]:
            _, target, request, form, via_stream = self.motion_end
            self.motion_end = None
            self.posture = target
            self.answer(request, form, via_stream, value=("string", target))
        if self.posture == "walking":
            self.battery -= 0.00001
        if self.loss.enabled() and not self.loss.announced and now >= self.loss.start_at:
            self.loss.announced = True
            self.report.check("2", "lossy-link", True, "from now on dropping %s of the datagrams received and of the "
                              "stream segments sent (seed %d)" % (
                                  "every %d-th" % self.args.loss_every if self.args.loss_every else "%.0f %%" % (100 * self.args.loss),
                                  self.args.loss_seed))
            print("loss on", flush=True)
        if now >= self.next_keepalive:
            self.next_keepalive = now + 0.2
            self.keepalive()
            # A hostile frame halfway between two good keep-alives.
            if self.hostile_cases and now >= self.hostile_at:
                self.next_hostile = now + 0.1
        if self.next_hostile is not None and now >= self.next_hostile:
            self.next_hostile = None
            self.send_hostile(now)
        self.debug_output(now)
        # Robot -> gateway stream data: a few keep-alive frames through the stream, one a second (11).
        # With --stream-queue they are offered at the interval whether or not the previous one is acknowledged, so
        # they queue up behind losses.
        if self.stream_sends_left > 0 and now >= self.next_stream_send and (self.stream.in_flight is None or self.args.stream_queue):
            self.stream_sends_left -= 1
            self.next_stream_send = now + self.args.stream_interval
            m = self.message()
            h = m.Extensions[self.pb_msg.robotHealth]
            h.posture, h.uptimeMs, h.bootId = self.posture, self.uptime_ms(), self.boot_id
            self.stream_offered.append(h.uptimeMs)
            self.stream_offer(self.frame(m))
        self.stream_pump(now)

    def run(self):
        self.start = time.monotonic()
        end = self.start + self.args.duration
        self.loss.start_at = self.start + self.args.loss_start
        if self.args.hostile_start >= 0:
            self.hostile_cases = list(HOSTILE_CASES) * self.args.hostile_rounds
            self.hostile_at = self.start + self.args.hostile_start
        socks = [self.recv_sock, self.send_sock]
        while not self.stop_flag and time.monotonic() < end:
            now = time.monotonic()
            readable, _, _ = select.select(socks, [], [], 0.01)
            for sock in readable:
                data, source = sock.recvfrom(65535)
                where = "3838" if sock is self.recv_sock else "send"
                self.data_segment_again(data)
                if self.loss.drop("in", time.monotonic()) or self.first_data_segment(data, time.monotonic()):
                    self.lost(data, source, where)
                    continue
                self.received(data, source, where)
                if self.pending_restart:
                    self.pending_restart = None
                    self.restart()
            self.tick(time.monotonic())
        self.finish()

    def finish(self):
        """End-of-run checks: what should have happened at least once."""
        c = self.counts
        self.report.check("2", "gateway-sends-to-port-3838", c["on3838"] > 0 or (c["onsend"] == 0),
                          "%d datagrams on 3838, %d on the sending port" % (c["on3838"], c["onsend"]))
        if self.active_before_restart:
            self.report.check("8", "re-enabled-after-restart", bool(self.reenabled_after_restart),
                              "active before the restart: %s, enabled now: %s" % (sorted(self.active_before_restart), sorted(self.enabled)))
        if self.stream.in_flight is not None:
            seq, _, first, sends = self.stream.in_flight
            # One first sent in the run's last seconds may be lost and not yet sent again (11.5), as the lost-segment
            # check above allows.
            if time.monotonic() - first > 3.0:
                self.report.check("11.4", "data-segments-answered", False, "seq %d still unacknowledged %.1f s after it was first sent (%d sends)" % (
                    seq, time.monotonic() - first, sends))
        if self.loss.enabled():
            end = time.monotonic()
            for t, seq, payload in self.dropped_segments:
                if end - t > 3.0:
                    self.report.check("11.5", "lost-data-segment-sent-again", False,
                                      "seq %d (%d payload bytes) dropped %.1f s before the end never arrived again" % (seq, len(payload), end - t))
            self.report.check("11.5", "retransmissions-after-loss", c["data_segments_sent_again"] + c["stream_duplicates_received"] > 0,
                              "%d dropped data segments sent again, %d duplicates received after dropped ACKs, %d resends by the robot" % (
                                  c["data_segments_sent_again"], c["stream_duplicates_received"], c["stream_resends"]))
            self.report.check("7.1", "dropped-calls-called-again", c["retries_seen"] > 0,
                              "%d requests dropped, %d arrived again as new Requests" % (c["requests_dropped"], c["retries_seen"]))
        self.report.check("11", "robot-stream-payloads", True, "uptimeMs " + " ".join(str(u) for u in self.stream_offered))
        self.report.check("summary", "counts", True, json.dumps(dict(c, restarts=self.restarts, bootId=self.boot_id,
                                                                      stream_data_sent=self.stream.sent_data,
                                                                      received_seen=self.loss.seen["in"], received_dropped=self.loss.dropped["in"],
                                                                      segments_sent_seen=self.loss.seen["out"],
                                                                      segments_sent_dropped=self.loss.dropped["out"])))
        self.report.close()
        self.log.close()


class BadParams(Exception):
    """A request whose parameters do not fit the method (7.4, `bad parameters: `)."""


class RobotError(Exception):
    """A request the robot refuses with one of the other prefixes of 7.4; the text is the whole error."""


def main():
    p = argparse.ArgumentParser(description="naogateway conformance robot (written from docs/protocol.md)")
    p.add_argument("--robot-id", type=int, required=True)
    p.add_argument("--address", required=True, help="the robot's own address, e.g. 127.0.0.43")
    p.add_argument("--port", type=int, default=3838, help="receive port (section 2: 3838)")
    p.add_argument("--gateway", required=True, help="host:port the robot sends to (section 2: UDP 11011)")
    p.add_argument("--team", type=int, default=12)
    p.add_argument("--player", type=int, default=3)
    p.add_argument("--boot-id", type=int, default=1)
    p.add_argument("--battery", type=float, default=12.4)
    p.add_argument("--forms", default="legacy,compact,legacy-gzip,compact-gzip", help="keep-alive header forms, in turn")
    p.add_argument("--stream-sends", type=int, default=5, help="keep-alive frames sent through the stream per session")
    p.add_argument("--stream-start", type=float, default=2.0, help="seconds after each power-up before the first stream payload")
    p.add_argument("--stream-interval", type=float, default=1.0, help="seconds between stream payloads")
    p.add_argument("--stream-queue", action="store_true", help="offer stream payloads without waiting for the previous ACK")
    p.add_argument("--loss", type=float, default=0.0, help="share of received datagrams and sent stream segments dropped")
    p.add_argument("--loss-seed", type=int, default=1, help="seed of the lossy link's random drops")
    p.add_argument("--loss-every", type=int, default=0, help="instead of --loss: drop every n-th datagram of each direction")
    p.add_argument("--loss-start", type=float, default=0.0, help="seconds after the start before the link turns lossy")
    p.add_argument("--hostile-start", type=float, default=-1.0, help="seconds after the start before the hostile frames (off if < 0)")
    p.add_argument("--hostile-rounds", type=int, default=2, help="how often each hostile frame is sent")
    p.add_argument("--restart-silence", type=float, default=4.0)
    p.add_argument("--duration", type=float, default=110.0, help="the robot exits by itself after this many seconds")
    p.add_argument("--report", required=True)
    p.add_argument("--log", required=True)
    p.add_argument("--proto", required=True, help="proto/src/main/protobuf of the checkout")
    p.add_argument("--gen", required=True, help="folder for the generated classes")
    args = p.parse_args()
    robot = Robot(args, load_classes(args.proto, args.gen))

    def stop(*_):
        robot.stop_flag = True

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    print("ready %s:%d sending from %d" % (args.address, args.port, robot.send_sock.getsockname()[1]), flush=True)
    robot.run()


if __name__ == "__main__":
    main()
