"""The official ROBOTIS DynamixelSDK (protocol 1.0, unmodified) against a Dynamixel bus reached through a serial device
(a socat pseudo-terminal in front of the emulated bus or the gateway's bus bridge, docs/protocol.md 6.9).

It pings every servo id given (and the HaViMo2 at id 100 with --camera), reads their control tables, writes a goal
position and moving speed to one servo and reads the present position until it arrives. It prints one JSON line with
what it found and exits 0 only when everything answered as an AX-12A bus of the project should.

    python sdk_bus.py --device /tmp/ttyDXL --ids 1-18 --goal-id 2 --goal 700 [--latency-ms 100] [--camera]
"""

import argparse
import json
import sys
import time

import dynamixel_sdk
from dynamixel_sdk import port_handler

ADDR_MODEL_NUMBER = 0
ADDR_ID = 3
ADDR_STATUS_RETURN_LEVEL = 16
ADDR_TORQUE_ENABLE = 24
ADDR_GOAL_POSITION = 30
ADDR_MOVING_SPEED = 32
ADDR_PRESENT_POSITION = 36
ADDR_PRESENT_VOLTAGE = 42
ADDR_PRESENT_TEMPERATURE = 43
AX12A_MODEL = 12
HAVIMO2_ID = 100


def ids(text):
    first, _, last = text.partition("-")
    return list(range(int(first), int(last or first) + 1))


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--device", required=True)
    parser.add_argument("--baud", type=int, default=1000000)
    parser.add_argument("--ids", type=ids, default=ids("1-18"))
    parser.add_argument("--goal-id", type=int, default=2)
    parser.add_argument("--goal", type=int, default=700)
    parser.add_argument("--speed", type=int, default=300)
    parser.add_argument("--camera", action="store_true")
    # The SDK's packet timeout is 2 x LATENCY_TIMER + 2 ms + the bytes' time (port_handler.py, 16 ms by default: a USB
    # serial adapter's latency). Over WiFi the round trip is longer: raise it.
    parser.add_argument("--latency-ms", type=float, default=None)
    parser.add_argument("--within", type=float, default=20.0, help="seconds the goal may take to be reached")
    args = parser.parse_args()

    if args.latency_ms is not None:
        port_handler.LATENCY_TIMER = args.latency_ms

    port = dynamixel_sdk.PortHandler(args.device)
    packets = dynamixel_sdk.PacketHandler(1.0)
    report = {"pinged": {}, "failures": []}

    def fail(what):
        report["failures"].append(what)

    if not port.openPort() or not port.setBaudRate(args.baud):
        fail("cannot open %s" % args.device)
        print(json.dumps(report))
        return 1

    def retried(call, *rest):
        # A lost datagram on the WiFi shows as one timeout: the tool tries again, as a calibration tool would.
        for _ in range(3):
            value = call(port, *rest)
            if value[-2] == dynamixel_sdk.COMM_SUCCESS:
                return value
        return value

    for dxl_id in args.ids:
        model, result, error = retried(packets.ping, dxl_id)
        if result != dynamixel_sdk.COMM_SUCCESS:
            fail("ping %d: %s" % (dxl_id, packets.getTxRxResult(result)))
            continue
        report["pinged"][str(dxl_id)] = model
        if model != AX12A_MODEL:
            fail("id %d reports model %d, not the AX-12A's %d" % (dxl_id, model, AX12A_MODEL))
        read_id, result, error = retried(packets.read1ByteTxRx, dxl_id, ADDR_ID)
        if result != dynamixel_sdk.COMM_SUCCESS or read_id != dxl_id:
            fail("id %d reads its id as %r (%s)" % (dxl_id, read_id, packets.getTxRxResult(result)))
        level, result, error = retried(packets.read1ByteTxRx, dxl_id, ADDR_STATUS_RETURN_LEVEL)
        if result != dynamixel_sdk.COMM_SUCCESS or level != 2:
            fail("id %d status return level %r" % (dxl_id, level))
        volts, result, error = retried(packets.read1ByteTxRx, dxl_id, ADDR_PRESENT_VOLTAGE)
        if result != dynamixel_sdk.COMM_SUCCESS or not 60 <= volts <= 140:
            fail("id %d present voltage %r" % (dxl_id, volts))

    if args.camera:
        model, result, error = retried(packets.ping, HAVIMO2_ID)
        if result != dynamixel_sdk.COMM_SUCCESS:
            fail("ping of the HaViMo2: %s" % packets.getTxRxResult(result))
        else:
            report["pinged"][str(HAVIMO2_ID)] = model
            record, result, error = retried(packets.readTxRx, HAVIMO2_ID, 16, 16)
            report["camera_slot_1"] = list(record) if result == dynamixel_sdk.COMM_SUCCESS else None

    if args.goal_id in args.ids and not report["failures"]:
        for address, value in ((ADDR_MOVING_SPEED, args.speed), (ADDR_GOAL_POSITION, args.goal)):
            result, error = retried(packets.write2ByteTxRx, args.goal_id, address, value)
            if result != dynamixel_sdk.COMM_SUCCESS or error != 0:
                fail("write %d at %d: %s, error %d" % (value, address, packets.getTxRxResult(result), error))
        torque, result, error = retried(packets.read1ByteTxRx, args.goal_id, ADDR_TORQUE_ENABLE)
        if torque != 1:
            fail("torque enable %r after a goal was written" % torque)
        deadline = time.monotonic() + args.within
        positions = []
        while time.monotonic() < deadline:
            position, result, error = retried(packets.read2ByteTxRx, args.goal_id, ADDR_PRESENT_POSITION)
            if result == dynamixel_sdk.COMM_SUCCESS:
                positions.append(position)
                if position == args.goal:
                    break
            time.sleep(0.05)
        report["positions"] = positions[:3] + positions[-3:]
        if not positions or positions[-1] != args.goal:
            fail("present position %r never reached the goal %d" % (positions[-1:] or None, args.goal))
        elif len(set(positions)) < 2:
            fail("present position did not move: %r" % positions)
        goal, result, error = retried(packets.read2ByteTxRx, args.goal_id, ADDR_GOAL_POSITION)
        if goal != args.goal:
            fail("goal position reads back %r" % goal)

    port.closePort()
    print(json.dumps(report))
    return 0 if not report["failures"] else 1


if __name__ == "__main__":
    sys.exit(main())
