#!/usr/bin/env python3
"""firmware/tools/bridge_check.py: the posix robot's bus bridge (docs/protocol.md 6.9) over real UDP, with this
script as the gateway: it starts build/posix-w1/robot as an unsigned development build with the emulated bus in
process (FR_POSIX_BUS=model), sends busBridge requests as secure-stream segments (11.1) and checks the replies:
a ping of servo 1, a read of its present position, the HaViMo2's ping, a malformed request, and one sent as a plain
datagram, which is never answered. Prints "N passed, N failed".

    bridge_check.py <path to build/posix-w1/robot>"""
import os
import socket
import subprocess
import sys
import tempfile
import time

from checks import Checks

CHECKS = Checks()
check = CHECKS.check
MAX_SEQ = 20


def varint(v):
    out = bytearray()
    while True:
        b = v & 0x7F
        v >>= 7
        out.append(b | (0x80 if v else 0))
        if not v:
            return bytes(out)


def fields(data):
    """The top-level fields of a protobuf message: (number, value) with ints and bytes."""
    k, out = 0, []
    while k < len(data):
        key, shift = 0, 0
        while True:
            b = data[k]; k += 1
            key |= (b & 0x7F) << shift; shift += 7
            if not b & 0x80:
                break
        number, wire = key >> 3, key & 7
        if wire == 0:
            v, shift = 0, 0
            while True:
                b = data[k]; k += 1
                v |= (b & 0x7F) << shift; shift += 7
                if not b & 0x80:
                    break
            out.append((number, v))
        elif wire == 2:
            n, shift = 0, 0
            while True:
                b = data[k]; k += 1
                n |= (b & 0x7F) << shift; shift += 7
                if not b & 0x80:
                    break
            out.append((number, data[k:k + n])); k += n
        elif wire == 5:
            out.append((number, data[k:k + 4])); k += 4
        elif wire == 1:
            out.append((number, data[k:k + 8])); k += 8
        else:
            raise ValueError("wire type %d" % wire)
    return out


def frame(robot_id, sequence, request):
    bridge = b"\x08" + varint(sequence) + b"\x12" + varint(len(request)) + request
    message = b"\x08" + varint(robot_id) + varint(7107 << 3 | 2) + varint(len(bridge)) + bridge
    return b"\x00\x2a\x00\x00" + len(message).to_bytes(4, "big") + message  # the compact header


def main():
    robot_bin = sys.argv[1]
    gw = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    gw.bind(("127.0.0.1", 0))
    gw.settimeout(0.05)
    port = gw.getsockname()[1]
    robot_addr = ("127.0.0.81", 3838)
    env = dict(os.environ, FR_POSIX_BIND="%s:%d" % robot_addr, FR_POSIX_BUS="model")
    tmp = tempfile.TemporaryDirectory(prefix="bridge-check-")  # removed at the end, or at exit should Popen fail
    epoch = os.path.join(tmp.name, "robot.epoch")
    robot = subprocess.Popen([robot_bin, "id=4", "gateway=127.0.0.1:%d" % port, "development", "run_ms=20000",
                              "epoch=" + epoch], env=env, stderr=subprocess.DEVNULL)
    seq = 0  # the gateway's next data segment
    robot_last = MAX_SEQ  # the last robot segment received in order

    def request(sequence, packet, plain=False):
        nonlocal seq
        f = frame(4, sequence, packet)
        if plain:
            gw.sendto(f, robot_addr)
            return
        gw.sendto(bytes([seq, robot_last]) + f, robot_addr)
        seq = (seq + 1) % (MAX_SEQ + 1)

    def reply(timeout=2.0):
        """The next busBridge reply from the robot's stream segments (ACKing them), or None."""
        nonlocal robot_last
        end = time.time() + timeout
        while time.time() < end:
            try:
                data, _ = gw.recvfrom(2000)
            except socket.timeout:
                continue
            if len(data) <= 2 or data[0] >= 42 or data[1] >= 42:
                continue  # keep-alives, pure ACKs
            robot_last = data[0]
            gw.sendto(bytes([(seq - 1) % (MAX_SEQ + 1), robot_last]), robot_addr)  # a pure ACK
            payload = data[2:]
            body = payload[12:] if int.from_bytes(payload[4:8], "big") == 0 else payload[8:]
            for number, value in fields(body):
                if number == 7107:
                    got = dict(fields(value))
                    return got.get(1), got.get(4, 0), got.get(3, b"")
        return None

    try:
        time.sleep(0.3)
        request(1, bytes.fromhex("FFFF010201FB"))
        check(reply() == (1, 0, bytes.fromhex("FFFF010200FC")), "ping servo 1")
        request(2, bytes.fromhex("FFFF0104022402D2"))  # read 2 bytes from 36
        r = reply()
        check(r is not None and r[0] == 2 and r[1] == 0 and r[2][5:7] == b"\x00\x02", "present position 512: %r" % (r,))
        request(3, bytes.fromhex("FFFF64020198"))
        r = reply()
        check(r is not None and r[0] == 3 and r[1] in (0, 1), "the HaViMo2 answers or is busy: %r" % (r,))
        request(4, bytes.fromhex("FFFF010201FA"))
        check(reply() == (4, 3, b""), "a wrong checksum is BUS_MALFORMED")
        request(5, bytes.fromhex("FFFF010201FB"), plain=True)
        check(reply(0.5) is None, "a plain datagram is not answered")
        request(6, bytes.fromhex("FFFF020201FA"))
        check(reply() == (6, 0, bytes.fromhex("FFFF020200FB")), "ping servo 2 after it")
    finally:
        robot.terminate()
        robot.wait(timeout=5)
        tmp.cleanup()
    return CHECKS.summary()


if __name__ == "__main__":
    sys.exit(main())
