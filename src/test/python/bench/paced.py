"""The bench scripts' one way to time an operation: paced calls after a warm-up, nearest-rank percentiles in
microseconds, and the one JSON line bench.CallPathBench reads."""

from __future__ import annotations

import json
import time
from typing import Callable, List


def percentile(samples: List[int], p: float) -> float:
    """Nearest-rank percentile, as the Scala bench computes it."""
    ordered = sorted(samples)
    return float(ordered[max(0, int(-(-p * len(ordered) // 1)) - 1)])


def paced(op: Callable[[], object], warmup: int, samples: int, gap_ms: float) -> List[int]:
    """Runs `op` warmup + samples times, one start per gap_ms at most; the last `samples` durations in nanoseconds."""
    taken: List[int] = []
    for i in range(warmup + samples):
        start = time.perf_counter_ns()
        op()
        took = time.perf_counter_ns() - start
        if i >= warmup:
            taken.append(took)
        rest = start + int(gap_ms * 1e6) - time.perf_counter_ns()
        if rest > 0:
            time.sleep(rest / 1e9)
    return taken


def figures(samples: List[int], **extra: object) -> str:
    """The JSON line of a run: p50 and p99 in microseconds, the sample count, and `extra`."""
    line = {"p50_us": percentile(samples, 0.50) / 1e3, "p99_us": percentile(samples, 0.99) / 1e3, "n": len(samples)}
    line.update(extra)
    return json.dumps(line)
