"""The bench's peer (bench.CallPathBench): MAVSDK's command round trip on loopback, in this process.

A pymavlink-played vehicle (a process of its own: a heartbeat as an autopilot, every COMMAND_LONG answered at once
with a COMMAND_ACK "accepted") and MAVSDK's ground side arming it N times; each arm is one command sent and its
acknowledgement awaited. The ground side is the `mavsdk` package (since version 4 the native library, in this process),
or with --grpc the gRPC one, `mavsdk-grpc` (MAVSDK-Python as `mavsdk` was up to version 3: this process asks the
bundled mavsdk_server, a process of its own, over gRPC). Prints one JSON line: {"p50_us": ..., "p99_us": ..., "n": ..., "version": ...}
or {"error": "..."} when MAVSDK cannot be used here.
"""

from __future__ import annotations

import argparse
import json
import os
import socket
import subprocess
import sys
import threading
import time
from typing import List
from paced import figures, paced

os.environ.setdefault("MAVLINK20", "1")


def free_udp_port() -> int:
    """A UDP port on loopback that nothing holds now."""
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


class Vehicle:
    """An autopilot in one thread: heartbeats at 1 Hz, an ACK for every COMMAND_LONG."""

    def __init__(self, port: int) -> None:
        from pymavlink import mavutil

        self.mavutil = mavutil
        self.link = mavutil.mavlink_connection("udpout:127.0.0.1:%d" % port, source_system=1, source_component=1)
        self.running = True
        self.acks = 0
        self.thread = threading.Thread(target=self.run, name="vehicle", daemon=True)

    def heartbeat(self) -> None:
        m = self.mavutil.mavlink
        self.link.mav.heartbeat_send(m.MAV_TYPE_QUADROTOR, m.MAV_AUTOPILOT_GENERIC, 0, 0, m.MAV_STATE_STANDBY)

    def run(self) -> None:
        m = self.mavutil.mavlink
        next_beat = 0.0
        while self.running:
            now = time.monotonic()
            if now >= next_beat:
                self.heartbeat()
                next_beat = now + 1.0
            msg = self.link.recv_match(blocking=True, timeout=0.05)
            if msg is not None and msg.get_type() == "COMMAND_LONG":
                self.link.mav.command_ack_send(msg.command, m.MAV_RESULT_ACCEPTED, 0, 0, msg.get_srcSystem(), msg.get_srcComponent())
                self.acks += 1

    def stop(self) -> None:
        self.running = False
        self.thread.join(2.0)
        self.link.close()



def free_tcp_port() -> int:
    """A TCP port on loopback that nothing holds now (mavsdk_server's gRPC port)."""
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def grpc_peer(args: argparse.Namespace) -> int:
    """The same arms through mavsdk-grpc: Python asks mavsdk_server over gRPC, mavsdk_server asks the vehicle."""
    try:
        import asyncio

        import mavsdk_grpc
    except Exception as e:  # noqa: BLE001 - any import failure means: not measured
        print(json.dumps({"error": "mavsdk-grpc cannot be imported: %s: %s" % (type(e).__name__, e)}))
        return 0
    port = free_udp_port()
    vehicle = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--vehicle", str(port)], stdin=subprocess.PIPE)

    async def arms() -> List[int]:
        drone = mavsdk_grpc.System(port=free_tcp_port())
        await asyncio.wait_for(drone.connect(system_address="udpin://127.0.0.1:%d" % port), 30)

        async def connected() -> None:
            async for state in drone.core.connection_state():
                if state.is_connected:
                    return

        await asyncio.wait_for(connected(), 30)
        samples: List[int] = []
        for i in range(args.warmup + args.samples):
            start = time.perf_counter_ns()
            await drone.action.arm()
            took = time.perf_counter_ns() - start
            if i >= args.warmup:
                samples.append(took)
            rest = start + int(args.gap_ms * 1e6) - time.perf_counter_ns()
            if rest > 0:
                await asyncio.sleep(rest / 1e9)
        return samples

    try:
        print(figures(asyncio.run(arms())))
    except Exception as e:  # noqa: BLE001 - reported, never a made-up figure
        print(json.dumps({"error": "mavsdk-grpc command failed: %s: %s" % (type(e).__name__, e)}))
    finally:
        vehicle.stdin.close()
        try:
            vehicle.wait(5)
        except subprocess.TimeoutExpired:
            vehicle.kill()
    return 0


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--warmup", type=int, default=200)
    parser.add_argument("--samples", type=int, default=1000)
    parser.add_argument("--gap-ms", type=float, default=1.0)
    parser.add_argument("--grpc", action="store_true", help="the gRPC ground side (mavsdk-grpc, mavsdk_server)")
    parser.add_argument("--vehicle", type=int, help="play the vehicle, sending to this port, until stdin closes")
    args = parser.parse_args()
    if args.vehicle is not None:
        played = Vehicle(args.vehicle)
        played.thread.start()
        sys.stdin.read()
        played.stop()
        return 0
    if args.grpc:
        return grpc_peer(args)
    try:
        import mavsdk
        from mavsdk import ComponentType, Configuration, Mavsdk
        from mavsdk.plugins.action import Action
    except Exception as e:  # noqa: BLE001 - any import failure means: not measured
        print(json.dumps({"error": "mavsdk cannot be imported: %s: %s" % (type(e).__name__, e)}))
        return 0
    port = free_udp_port()
    drone = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    result = drone.add_any_connection("udpin://127.0.0.1:%d" % port)
    vehicle = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--vehicle", str(port)], stdin=subprocess.PIPE)
    try:
        system = drone.first_autopilot(10.0)
        if system is None:
            print(json.dumps({"error": "MAVSDK saw no autopilot within 10 s (connection: %s)" % (result,)}))
            return 0
        action = Action(system)
        samples = paced(action.arm, args.warmup, args.samples, args.gap_ms)
        print(figures(samples, version=getattr(mavsdk, "__version__", "?")))
        return 0
    except Exception as e:  # noqa: BLE001 - reported, never a made-up figure
        print(json.dumps({"error": "MAVSDK command failed: %s: %s" % (type(e).__name__, e)}))
        return 0
    finally:
        vehicle.stdin.close()
        try:
            vehicle.wait(5)
        except subprocess.TimeoutExpired:
            vehicle.kill()


if __name__ == "__main__":
    sys.exit(main())
