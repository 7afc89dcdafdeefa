"""Stands a robot up, walks it briefly, stops it and prints its status, through the naogateway ZeroMQ endpoint.

Against the demo (./sbt run or bin/naogateway: robots 1 to 3, the ball follower steering robot 1):

    python3 example_walk.py [--robot 2] [--endpoint tcp://127.0.0.1:5555] [--publish tcp://127.0.0.1:5556]
"""

from __future__ import annotations

import argparse
import sys
import time

import naogateway_client
from naogateway_client import GatewayClient, GatewayError


def wait_for_robot(client: GatewayClient, robot_id: int, timeout: float) -> None:
    """Waits until the gateway knows the robot and it is online."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if robot_id in client.robots():
            try:
                if client.status(robot_id)["online"]:
                    return
            except GatewayError:
                pass
        time.sleep(0.2)
    raise SystemExit("robot %d did not come online within %.0f s" % (robot_id, timeout))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--endpoint", default="tcp://127.0.0.1:5555")
    parser.add_argument("--publish", default="tcp://127.0.0.1:5556")
    parser.add_argument("--robot", type=int, default=2, help="the robot to walk (default 2: the demo's ball follower has robot 1)")
    parser.add_argument("--seconds", type=float, default=1.0, help="how long to walk")
    args = parser.parse_args()

    naogateway_client.load_protos()
    client = GatewayClient(args.endpoint, args.publish)
    try:
        wait_for_robot(client, args.robot, timeout=20)
        print("robots:", client.robots())
        # The endpoint takes the walk lease for us; the robot must stand before it can walk.
        print("posture:", client.posture(args.robot, "stand"))
        client.walk(args.robot, 0.1, 0.0, 0.0)
        print("walking at 0.1 m/s for %.1f s" % args.seconds)
        time.sleep(args.seconds)
        client.stop(args.robot)
        print("stopped")
        status = client.next_status(args.robot, timeout=5.0, where=lambda s: s["posture"] not in (None, "walking"))
        if status is None:
            print("no status published for robot %d" % args.robot)
            return 1
        print("status of robot %d: battery %.2f V, posture %s, link %s"
              % (args.robot, status["battery"], status["posture"], status["link"]))
        client.release(args.robot, "walk")
        return 0
    except GatewayError as e:
        print("error:", e.text)
        return 1
    finally:
        client.close()


if __name__ == "__main__":
    sys.exit(main())
