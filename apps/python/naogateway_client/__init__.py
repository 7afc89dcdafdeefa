"""A client of the naogateway ZeroMQ endpoint and of its datagram door (docs/zeromq.md).

GatewayClient: requests go to the endpoint's ROUTER socket from a DEALER socket: one serialized
naogateway.proto.Message with an rpcRequest per ZeroMQ message, answered with a Message carrying the rpcResponse with
the same callId. Robot data comes from the endpoint's publish socket on the topics status.<robotId>, vision.<robotId>
and game.

DatagramGatewayClient: the same requests and replies, each one UDP datagram to and from the datagram door
(apps.datagram-door): the lowest latency for calls from the same machine, no streams. A lost datagram is a timeout;
only the requests that change nothing (robots, status) are sent again.

The protobuf classes are generated from the .proto files the package carries (proto/, the repository's
proto/src/main/protobuf) with grpcio-tools' protoc; see `load_protos`.
"""

from __future__ import annotations

import atexit
import importlib
import itertools
import os
import shutil
import socket
import sys
import tempfile
import time
from types import ModuleType
from typing import Any, Callable, Dict, List, Optional, Union

import zmq

_HERE = os.path.dirname(os.path.abspath(__file__))
_PROTO_DIR = os.path.join(_HERE, "proto")

Value = Union[bool, int, float, str, bytes, List[Any], None]
"""A value a robot call takes or returns (a protobuf MixedValue)."""

Status = Dict[str, Any]
"""A robot's status as a dict: robot, battery, posture, uptime_ms, role, link (and online, from `status`)."""
Servo = Dict[str, Any]
"""One servo of a robot's latest servo telemetry as a dict: id, position, degrees, load, voltage, temperature, error,
silent, hot, low_voltage (docs/protocol.md 6.8)."""
_PROTO_FILES = ["message.proto", "rpc.proto", "havimo.proto", "debugging.proto", "body.proto"]

# The gateway's names, as the endpoint takes and reports them (docs/zeromq.md); apps.zeromq.PythonNamesSpec checks
# them against the gateway's own types.
POSTURES = ("sit", "stand", "crouch", "walking", "moving", "fallen")
"""Every posture a robot reports (docs/protocol.md 7.2). A newer robot may report one not listed; status dicts carry it
as it came."""

POSTURE_TARGETS = ("sit", "stand", "crouch")
"""The postures `posture` may ask for; the endpoint answers any other name with a malformed-request error."""

ACTUATOR_GROUPS = ("walk", "head", "arms", "speech")
"""The lease groups of `acquire` and `release`: walk (walking and postures), head, arms, speech."""

message_pb2: Optional[ModuleType] = None
rpc_pb2: Optional[ModuleType] = None
havimo_pb2: Optional[ModuleType] = None
body_pb2: Optional[ModuleType] = None


def load_protos(out_dir: Optional[str] = None, proto_dir: str = _PROTO_DIR) -> None:
    """Imports the generated protobuf modules, generating them into out_dir first when they are not importable.

    out_dir defaults to $NAOGATEWAY_PY_GEN, else a fresh temporary folder, removed when the program exits.
    """
    global message_pb2, rpc_pb2, havimo_pb2, body_pb2
    out_dir = out_dir or os.environ.get("NAOGATEWAY_PY_GEN")
    if not out_dir:
        out_dir = tempfile.mkdtemp(prefix="naogateway-pb2-")
        # Each program without a folder of its own would otherwise leave one behind in the system's temporary folder.
        atexit.register(shutil.rmtree, out_dir, ignore_errors=True)
    if out_dir not in sys.path:
        sys.path.insert(0, out_dir)
    try:
        importlib.import_module("naogateway.proto.rpc_pb2")
        importlib.import_module("naogateway.proto.body_pb2")
    except ImportError:
        from grpc_tools import protoc  # only needed to generate

        os.makedirs(out_dir, exist_ok=True)
        args = ["protoc", "-I" + proto_dir, "--python_out=" + out_dir]
        args += ["naogateway/proto/" + f for f in _PROTO_FILES]
        if protoc.main(args) != 0:
            raise RuntimeError("protoc failed on " + proto_dir)
        importlib.invalidate_caches()
    message_pb2 = importlib.import_module("naogateway.proto.message_pb2")
    rpc_pb2 = importlib.import_module("naogateway.proto.rpc_pb2")
    havimo_pb2 = importlib.import_module("naogateway.proto.havimo_pb2")
    body_pb2 = importlib.import_module("naogateway.proto.body_pb2")


class GatewayError(Exception):
    """The endpoint answered with an error; `text` starts with its category, e.g. "lease: " or "offline: "."""

    def __init__(self, text: str) -> None:
        super().__init__(text)
        self.text = text
        self.category = text.split(":", 1)[0]


def to_mixed(value: Value, mixed: Any) -> Any:
    """Fills a MixedValue: bool, non-negative int, float (and negative int), str, bytes, list."""
    if isinstance(value, bool):
        mixed.bool = value
    elif isinstance(value, int) and 0 <= value <= 0xFFFFFFFF:
        mixed.int = value
    elif isinstance(value, (int, float)):
        mixed.float = float(value)
    elif isinstance(value, str):
        mixed.string = value
    elif isinstance(value, (bytes, bytearray)):
        mixed.binary = bytes(value)
    elif isinstance(value, (list, tuple)):
        for item in value:
            to_mixed(item, mixed.array.add())
    else:
        raise TypeError("cannot send %r" % (value,))
    return mixed


def from_mixed(mixed: Any) -> Value:
    """The Python value of a MixedValue (an empty one is an empty list)."""
    for field in ("string", "int", "float", "binary", "bool"):
        if mixed.HasField(field):
            return getattr(mixed, field)
    return [from_mixed(m) for m in mixed.array]


def snapshot_of(message: Any, link: Optional[str] = None) -> Status:
    """A dict of a Message with status and robotHealth: robot, battery, posture, uptime_ms, ..."""
    status = message.Extensions[message_pb2.status]
    health = message.Extensions[message_pb2.robotHealth]
    return {
        "robot": message.robotID,
        "battery": health.batteryVoltage if health.HasField("batteryVoltage") else None,
        "posture": health.posture if health.HasField("posture") else (status.currentState or None),
        "uptime_ms": health.uptimeMs if health.HasField("uptimeMs") else None,
        "role": status.activeRole or None,
        "link": link,
    }


class _Calls:
    """The calls both clients make: a request is built and its reply read here; each transport carries them."""

    timeout: float

    def __init__(self, timeout: float) -> None:
        if rpc_pb2 is None:
            load_protos()
        self.timeout = timeout
        self._ids = itertools.count(1)
        self.last_reply: Any = None

    def _exchange(self, request: bytes, call_id: int, idempotent: bool, what: str) -> Any:
        """Sends the request and returns the parsed reply Message with this call_id; raises a timeout GatewayError."""
        raise NotImplementedError

    def call(self, robot_id: int, module: str, method: str, *params: Value) -> Value:
        """Calls module.method on robot robot_id; returns the value or raises GatewayError."""
        call_id = next(self._ids) & 0xFFFFFFFF
        message = message_pb2.Message(robotID=robot_id)
        request = message.Extensions[rpc_pb2.rpcRequest]
        request.module = module
        request.method = method
        request.callId = call_id
        for p in params:
            to_mixed(p, request.params.add())
        idempotent = (module, method) in _IDEMPOTENT
        reply = self._exchange(message.SerializeToString(), call_id, idempotent, "%s.%s" % (module, method))
        response = reply.Extensions[rpc_pb2.rpcResponse]
        if response.HasField("error"):
            raise GatewayError(response.error)
        self.last_reply = reply
        return from_mixed(response.returnval) if response.HasField("returnval") else None

    @staticmethod
    def _reply_to(body: bytes, call_id: int) -> Any:
        """The reply Message in body when it answers call_id, else None (the late reply of an earlier call)."""
        reply = message_pb2.Message()
        reply.ParseFromString(body)
        return reply if reply.Extensions[rpc_pb2.rpcResponse].callId == call_id else None

    def send(self, robot_id: int, module: str, method: str, *params: Value) -> None:
        """Sends module.method to robot robot_id without waiting for the robot (the endpoint's gateway.send).

        Returns once the gateway accepted it, in order with this client's calls and sends; the robot's answer is
        dropped. Raises GatewayError when it is refused (lease, offline, safety, ...) as a call would.
        """
        self.call(robot_id, "gateway", "send", module, method, *params)

    # The endpoint's own methods.
    def robots(self) -> List[int]:
        """The ids of every robot the gateway knows."""
        return self.call(-1, "gateway", "robots")

    def status(self, robot_id: int) -> Status:
        """The robot's status as a dict: online and link as the gateway sees them now, posture as the robot answers it
        now (so right after stop it says stand), battery, uptime and role from its latest keep-alive."""
        online, link = self.call(robot_id, "gateway", "status")
        snapshot = snapshot_of(self.last_reply, link)
        snapshot["online"] = online
        return snapshot

    def servos(self, robot_id: int) -> List[Servo]:
        """The robot's latest servo telemetry, one dict per servo in the robot's order (empty before the first one),
        each marked hot or low_voltage by the middleware's limits (robotmiddleware.servos)."""
        hot, low = self.call(robot_id, "gateway", "servos")
        telemetry = self.last_reply.Extensions[body_pb2.servoTelemetry]
        out: List[Servo] = []
        for s in telemetry.servos:
            silent = s.HasField("silent") and s.silent
            position = s.position if s.HasField("position") and not silent else None
            out.append({
                "id": s.id,
                "position": position,
                "degrees": None if position is None else (position - 512) * 300.0 / 1023,
                "load": s.load if s.HasField("load") and not silent else None,
                "voltage": s.voltage / 10.0 if s.HasField("voltage") and not silent else None,
                "temperature": s.temperature if s.HasField("temperature") and not silent else None,
                "error": s.error if s.HasField("error") else 0,
                "silent": silent,
                "hot": s.id in hot,
                "low_voltage": s.id in low,
            })
        return out

    def acquire(self, robot_id: int, *groups: str) -> bool:
        """Takes the leases of these ACTUATOR_GROUPS on the robot, all of them or none."""
        return self.call(robot_id, "gateway", "acquire", *groups)

    def release(self, robot_id: int, *groups: str) -> bool:
        """Gives the leases of these ACTUATOR_GROUPS back."""
        return self.call(robot_id, "gateway", "release", *groups)

    # RobotInterface calls; the endpoint takes the lease each needs on the clients' behalf.
    def walk(self, robot_id: int, vx: float, vy: float, omega: float) -> bool:
        """Walks with these velocities (m/s, m/s, rad/s) until stopped; the endpoint keeps the walk fresh. Beyond the
        gateway's walk limits (0.3 m/s, 1.0 rad/s by default) a GatewayError "robot error: out of range: vx 100.0,
        allowed -0.3..0.3"."""
        return self.call(robot_id, "motion", "walk", float(vx), float(vy), float(omega))

    def stop(self, robot_id: int) -> bool:
        """Stops walking."""
        return self.call(robot_id, "motion", "stop")

    def head(self, robot_id: int, pan: float, tilt: float) -> bool:
        """Turns the head (radians; pan -2.0..2.0, tilt -0.6..0.5, else an "out of range:" GatewayError)."""
        return self.call(robot_id, "motion", "head", float(pan), float(tilt))

    def arms(self, robot_id: int, left_shoulder: float, left_elbow: float, right_shoulder: float, right_elbow: float) -> bool:
        """Sets the four arm joints (radians)."""
        values = [float(v) for v in (left_shoulder, left_elbow, right_shoulder, right_elbow)]
        return self.call(robot_id, "motion", "arms", *values)

    def posture(self, robot_id: int, name: str) -> str:
        """Goes to one of POSTURE_TARGETS; returns the posture reached once the motion has ended."""
        return self.call(robot_id, "motion", "posture", name)

    def say(self, robot_id: int, text: str) -> bool:
        """Speaks the text."""
        return self.call(robot_id, "speech", "say", text)


_IDEMPOTENT = frozenset([("gateway", "robots"), ("gateway", "status"), ("gateway", "servos")])
"""The requests that change nothing: the only ones DatagramGatewayClient sends again when no reply came."""


class GatewayClient(_Calls):
    """Calls the endpoint's methods and robot calls over ZeroMQ; reads the published topics."""

    def __init__(self, endpoint: str = "tcp://127.0.0.1:5555", publish: str = "tcp://127.0.0.1:5556", timeout: float = 10.0) -> None:
        super().__init__(timeout)
        self._context = zmq.Context()
        self._dealer = self._context.socket(zmq.DEALER)
        self._dealer.setsockopt(zmq.LINGER, 0)
        self._dealer.connect(endpoint)
        self._publish = publish
        self._sub: Optional[zmq.Socket] = None

    def _exchange(self, request: bytes, call_id: int, idempotent: bool, what: str) -> Any:
        # ZeroMQ loses nothing on a live connection: no request is sent twice.
        self._dealer.send_multipart([b"", request])
        deadline = time.monotonic() + self.timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0 or not self._dealer.poll(int(left * 1000)):
                raise GatewayError("timeout: no reply to %s within %.1f s" % (what, self.timeout))
            reply = self._reply_to(self._dealer.recv_multipart()[-1], call_id)
            if reply is not None:
                return reply

    # Published data.
    def subscribe(self, *topics: str) -> None:
        """Subscribes to topics (prefixes), e.g. "status.20", "vision.20", "game"."""
        if self._sub is None:
            self._sub = self._context.socket(zmq.SUB)
            self._sub.setsockopt(zmq.LINGER, 0)
            self._sub.connect(self._publish)
        for topic in topics:
            self._sub.setsockopt(zmq.SUBSCRIBE, topic.encode())

    def next_status(self, robot_id: int, timeout: float = 5.0, where: Callable[[Status], bool] = lambda s: True) -> Optional[Status]:
        """The next published status of robot_id that satisfies `where`, as a dict; None after timeout seconds."""
        topic = "status.%d" % robot_id
        self.subscribe(topic)
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0 or not self._sub.poll(int(left * 1000)):
                return None
            frames = self._sub.recv_multipart()
            if frames[0].decode() != topic:
                continue
            message = message_pb2.Message()
            message.ParseFromString(frames[1])
            snapshot = snapshot_of(message, frames[2].decode() if len(frames) > 2 else None)
            if where(snapshot):
                return snapshot

    def close(self) -> None:
        """Closes the sockets."""
        self._dealer.close()
        if self._sub is not None:
            self._sub.close()
        self._context.term()


class DatagramGatewayClient(_Calls):
    """Calls the endpoint's methods and robot calls through the datagram door: one UDP datagram each way.

    address is "host:port" or (host, port) of apps.datagram-door. A request without a reply within `timeout` seconds
    raises a timeout GatewayError. Only robots(), status() and servos() (which change nothing) are sent again, up to
    `retries` more times, `retry_interval` seconds apart, within the same `timeout`; a call, a send or a lease is never
    sent twice, so a timeout does not say whether the robot got it.
    """

    def __init__(self, address: Union[str, tuple] = "127.0.0.1:5557", timeout: float = 10.0, retries: int = 2,
                 retry_interval: float = 0.2) -> None:
        super().__init__(timeout)
        if isinstance(address, str):
            host, _, port = address.rpartition(":")
            address = (host or "127.0.0.1", int(port))
        if retries < 0 or retry_interval <= 0:
            raise ValueError("retries must be >= 0 and retry_interval > 0")
        self.address = address
        self.retries = retries
        self.retry_interval = retry_interval
        self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        # Connected: only the door's datagrams arrive here.
        self._socket.connect(address)

    def _exchange(self, request: bytes, call_id: int, idempotent: bool, what: str) -> Any:
        start = time.monotonic()
        deadline = start + self.timeout
        sends = 1 + (self.retries if idempotent else 0)
        self._socket.send(request)
        sends -= 1
        resend_at = start + self.retry_interval if sends > 0 else deadline
        while True:
            now = time.monotonic()
            if now >= deadline:
                raise GatewayError("timeout: no reply to %s within %.1f s from the datagram door at %s:%d" %
                                   ((what, self.timeout) + tuple(self.address)))
            if now >= resend_at:
                self._socket.send(request)
                sends -= 1
                resend_at = now + self.retry_interval if sends > 0 else deadline
            self._socket.settimeout(max(0.0005, min(deadline, resend_at) - now))
            try:
                body = self._socket.recv(65536)
            except socket.timeout:
                continue
            except ConnectionRefusedError:
                continue  # nothing listens yet (an ICMP answer to an earlier datagram): the deadline decides
            try:
                reply = self._reply_to(body, call_id)
            except Exception:
                continue  # not a reply: the door only ever sends Messages
            if reply is not None:
                return reply

    def close(self) -> None:
        """Closes the socket."""
        self._socket.close()
