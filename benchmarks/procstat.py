"""CPU time and core pinning of running processes, for the benchmarks that measure services
through their processes (benchmarks/network_centre.py, benchmarks/network_chain.py).

Linux only: /proc/<pid>/stat (utime + stime of every thread, clock ticks) and
os.sched_setaffinity on every thread of /proc/<pid>/task (Zenoh's runtime threads
included, so the whole process runs on the cores given).
"""

from __future__ import annotations

import os
from pathlib import Path

TICK = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid: int) -> float:
    """User + system CPU seconds of process `pid` so far (all its threads)."""
    stat = Path(f"/proc/{pid}/stat").read_text()
    fields = stat[stat.rindex(")") + 2:].split()  # after "pid (comm) "
    return (int(fields[11]) + int(fields[12])) / TICK


def pin(pid: int, cores: set[int]) -> int:
    """Every thread of process `pid` on `cores`; returns the number of threads pinned."""
    n = 0
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            os.sched_setaffinity(int(task.name), cores)
            n += 1
        except (ProcessLookupError, FileNotFoundError):
            continue
    return n


def host_load() -> str:
    """The host's 1, 5 and 15 minute load averages and its CPU count, as printed."""
    one, five, fifteen = os.getloadavg()
    return f"load {one:.2f} / {five:.2f} / {fifteen:.2f} on {os.cpu_count()} CPUs"
