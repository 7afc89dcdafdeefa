"""firmware/tools/checks.py: what the body's check scripts (sdk_check.py, qemu_bus_check.py, bridge_check.py) share:
the "N passed, N failed" tally the Scala specs read, a free loopback port, and the standalone busmodel started on one."""
import socket
import subprocess


class Checks:
    """Counts checks and prints the one summary line make's callers look for."""

    def __init__(self):
        self.passed = 0
        self.failed = 0

    def check(self, ok, what):
        if ok:
            self.passed += 1
        else:
            self.failed += 1
            print("FAIL", what)

    def summary(self):
        print("%d passed, %d failed" % (self.passed, self.failed))
        return 0 if self.failed == 0 else 1


def free_port():
    """A loopback port nothing listens on now."""
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def start_busmodel(binary, port, run_ms, *extra):
    """The standalone busmodel on 127.0.0.1:port, and the first line it printed ("busmodel: listening on ..." once
    ready)."""
    model = subprocess.Popen([binary, "port=%d" % port, "run_ms=%d" % run_ms] + list(extra), stdout=subprocess.PIPE,
                             text=True)
    return model, model.stdout.readline()
