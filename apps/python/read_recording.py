"""Prints what a gateway recording holds: one line per datagram, Status and decision (docs/recording.md).

    python read_recording.py recordings/naogateway-*.mcap
"""

import argparse
import json

from naogateway_recording import Recording


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("files", nargs="+", help="MCAP files of one recording, in order")
    args = parser.parse_args()
    rec = Recording(*args.files)
    for d in rec.datagrams():
        robot = "-" if d.robot_id is None else d.robot_id
        print(f"datagram {d.log_time_ns} {d.port} {d.direction} {d.source} {d.destination} robot {robot} {d.payload.hex()}")
    for robot_id, time_ns, status in rec.statuses():
        print(f"status {robot_id} {time_ns} team {status.teamID} agent {status.activeAgent} timestamp {status.timestamp}")
    for decision in rec.decisions():
        print("decision " + json.dumps(decision, sort_keys=True))


if __name__ == "__main__":
    main()
