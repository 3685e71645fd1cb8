"""Is the machine quiet enough to time on? Shared by the benchmarks.

The load average trails the past minutes (a benchmark started right after another one
sees ~1 on an idle machine), so this samples the CPU counters of /proc/stat instead: the
cores busy over a short window just before the timing starts.
"""

from __future__ import annotations

import os
import time

#: Busy cores (of all) above which timings are not to be trusted.
QUIET_CORES = 0.3


def _cpu_times() -> tuple[int, int] | None:
    """(busy, total) jiffies of all CPUs, or None where /proc/stat is not readable."""
    try:
        with open("/proc/stat") as f:
            fields = [int(v) for v in f.readline().split()[1:]]
    except (OSError, ValueError):
        return None
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)      # idle + iowait
    return sum(fields) - idle, sum(fields)


def busy_cores(seconds: float = 2.0) -> float | None:
    """Cores busy, on average, over the next ``seconds`` (None without /proc/stat)."""
    a = _cpu_times()
    time.sleep(seconds)
    b = _cpu_times()
    if a is None or b is None or b[1] == a[1]:
        return None
    return (b[0] - a[0]) / (b[1] - a[1]) * (os.cpu_count() or 1)


def check_quiet(what: str = "the timings below") -> float | None:
    """Print how busy the machine is right now; a warning when other work shares it."""
    busy = busy_cores()
    if busy is None:
        print("machine load unknown (no /proc/stat)", flush=True)
    elif busy > QUIET_CORES:
        print(f"WARNING: {busy:.2f} of {os.cpu_count()} cores busy before the start: other "
              f"work shares the machine, {what} are not to be trusted", flush=True)
    else:
        print(f"machine quiet before the start: {busy:.2f} of {os.cpu_count()} cores busy",
              flush=True)
    return busy
