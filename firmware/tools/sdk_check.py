#!/usr/bin/env python3
"""firmware/tools/sdk_check.py: the official ROBOTIS DynamixelSDK (protocol 1.0, unmodified) against an emulated bus
reached through a socat pseudo-terminal, as a base-station tool reaches a robot's bus.

    sdk_check.py <path to build/busmodel>     starts the standalone busmodel on a free loopback port and checks it
    sdk_check.py --connect 127.0.0.1:6102     checks whatever serves the bus there (e.g. the gateway's bridge)

It pings servos 1-18 (model number 12, the AX-12A) and the HaViMo2 at 100, finds nobody at 30, writes a goal
position to servo 2, reads it back and reads the servo arriving there, and prints "N passed, N failed"."""
import os
import subprocess
import sys
import tempfile
import time

from dynamixel_sdk import COMM_SUCCESS, PacketHandler, PortHandler

from checks import Checks, free_port, start_busmodel

CHECKS = Checks()
check = CHECKS.check


def main():
    procs = []
    tmp_dir = tempfile.TemporaryDirectory(prefix="sdk-check-")
    tmp = tmp_dir.name
    try:
        if sys.argv[1] == "--connect":
            target = sys.argv[2]
        else:
            port = free_port()
            model, line = start_busmodel(sys.argv[1], port, 120000)
            procs.append(model)
            check("listening" in line, "busmodel did not start: %r" % line)
            target = "127.0.0.1:%d" % port
        link = os.path.join(tmp, "dxl")
        procs.append(subprocess.Popen(["socat", "pty,link=%s,raw,echo=0" % link, "tcp:%s" % target]))
        for _ in range(100):
            if os.path.exists(link):
                break
            time.sleep(0.05)
        ph = PortHandler(link)
        check(ph.openPort(), "open the pseudo-terminal")
        check(ph.setBaudRate(1000000), "1 Mbps")
        pk = PacketHandler(1.0)
        for dxl_id in range(1, 19):
            model_number, result, error = pk.ping(ph, dxl_id)
            check(result == COMM_SUCCESS and error == 0 and model_number == 12, "ping %d: %s" % (dxl_id, pk.getTxRxResult(result)))
        _, result, error = pk.ping(ph, 100)
        check(result == COMM_SUCCESS, "ping the HaViMo2 at 100: %s" % pk.getTxRxResult(result))
        _, result, _ = pk.ping(ph, 30)
        check(result != COMM_SUCCESS, "nobody at 30")
        result, error = pk.write2ByteTxRx(ph, 2, 32, 300)  # moving speed
        check(result == COMM_SUCCESS and error == 0, "write moving speed")
        result, error = pk.write2ByteTxRx(ph, 2, 30, 700)  # goal position
        check(result == COMM_SUCCESS and error == 0, "write goal position: %s" % pk.getTxRxResult(result))
        goal, result, error = pk.read2ByteTxRx(ph, 2, 30)
        check(result == COMM_SUCCESS and goal == 700, "read the goal back: %s %r" % (pk.getTxRxResult(result), goal))
        present = None
        for _ in range(40):
            present, result, error = pk.read2ByteTxRx(ph, 2, 36)
            if result == COMM_SUCCESS and present == 700:
                break
            time.sleep(0.05)
        check(present == 700, "servo 2 reaches its goal: %r" % present)
        volts, result, _ = pk.read1ByteTxRx(ph, 7, 42)
        check(result == COMM_SUCCESS and volts == 120, "servo 7 at 12.0 V: %r" % volts)
        ph.closePort()
    finally:
        for p in procs:
            p.terminate()
            try:
                p.wait(timeout=5)
            except subprocess.TimeoutExpired:
                p.kill()
        tmp_dir.cleanup()
    return CHECKS.summary()


if __name__ == "__main__":
    sys.exit(main())
