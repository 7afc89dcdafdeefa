#!/usr/bin/env python3
"""firmware/tools/qemu_bus_check.py: the qemu board (build/qemu/robot.elf, development) with the standalone busmodel
on its first -serial (the netduino2's USART1) reads every servo and captures camera frames over it, for a few
seconds of emulation. Prints "N passed, N failed".

    qemu_bus_check.py <build/busmodel> <build/qemu/robot.elf>"""
import re
import subprocess
import sys
import tempfile
import time

from checks import Checks, free_port, start_busmodel

CHECKS = Checks()
check = CHECKS.check


def main():
    port = free_port()
    model, line = start_busmodel(sys.argv[1], port, 60000, "log=1")
    check("listening" in line, "busmodel started")
    tmp = tempfile.TemporaryDirectory(prefix="qemu-bus-")  # removed at the end, or at exit should Popen fail
    epoch = tmp.name + "/robot.epoch"
    qemu = subprocess.Popen(["qemu-system-arm", "-M", "netduino2", "-display", "none", "-monitor", "none", "-nodefaults",
                             "-serial", "tcp:127.0.0.1:%d,nodelay=on" % port, "-serial", "null", "-serial", "null",
                             "-serial", "null", "-serial", "null", "-semihosting-config", "enable=on,target=native",
                             "-kernel", sys.argv[2], "-append", "development epoch=%s" % epoch],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    best = (0, 0)
    try:
        end = time.time() + 30
        while time.time() < end and (best[0] < 18 or best[1] < 3):
            line = model.stdout.readline()  # once a second while qemu talks; EOF when the model ends (run_ms)
            m = re.search(r"(\d+) servos read, (\d+) captures", line)
            if m:
                best = (int(m.group(1)), int(m.group(2)))
    finally:
        qemu.terminate()
        model.terminate()
        qemu.wait(timeout=10)
        model.wait(timeout=10)
        tmp.cleanup()
    check(best[0] == 18, "every servo read: %d" % best[0])
    check(best[1] >= 3, "camera frames captured: %d" % best[1])
    return CHECKS.summary()


if __name__ == "__main__":
    sys.exit(main())
