"""What processes cost, read from /proc: CPU seconds, resident memory, their children, the load."""

from __future__ import annotations

import os
from pathlib import Path


def proc_stat(pid: int) -> tuple[float, int]:
    """(CPU seconds used, resident bytes) of process `pid`."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    ticks = os.sysconf("SC_CLK_TCK")
    cpu = (int(fields[11]) + int(fields[12])) / ticks
    rss = int(fields[21]) * os.sysconf("SC_PAGE_SIZE")
    return cpu, rss


def cpu_seconds(pids: list[int]) -> float:
    """CPU seconds used by these processes (those gone meanwhile count as nothing)."""
    total = 0.0
    for pid in pids:
        try:
            total += proc_stat(pid)[0]
        except OSError:
            pass
    return total


def children(pid: int) -> list[int]:
    try:
        return [int(p) for p in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]
    except OSError:
        return []


def descendants(pid: int) -> list[int]:
    """Every process below `pid` (children, their children ...)."""
    found, todo = [], children(pid)
    while todo:
        kid = todo.pop()
        found.append(kid)
        todo += children(kid)
    return found


def load_average() -> str:
    """The one-minute load average, as /proc/loadavg says it."""
    return Path("/proc/loadavg").read_text().split()[0]
