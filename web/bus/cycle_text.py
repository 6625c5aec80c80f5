"""What a CPU's cycle statistics (``CycleStats`` of ``status``) say, in words: the longest
and the last long cycle and where their time went, the share of the cycle for
communication, where the scan thread runs. The shell's ``status`` prints these lines and
the page's status line shows them as its tooltip; plain text, so the shell does not load
the page's drawing.
"""

from __future__ import annotations

import time

from s7graph.engine.profile import describe as describe_cycle
from s7graph.web.bus.protocol import CycleReport, CycleStats

__all__ = ["clock", "comm_line", "cycle_lines", "scan_thread_line"]


def cycle_lines(stats: CycleStats) -> list[str]:
    """Where the longest and the last long cycle went (``engine.profile``), one line each,
    none before the runner has measured a cycle; then the share for communication and where
    the scan thread runs (both from a runner's statistics only)."""
    lines = []
    if stats.longest is not None:
        lines.append(f"longest: {_cycle_line(stats.longest)}")
    if stats.last_long is not None:
        lines.append(
            f"last over {stats.long_over_ms:.1f} ms ({stats.long} so far): "
            f"{_cycle_line(stats.last_long)}"
        )
    if stats.comm_load:
        lines.append(comm_line(stats))
        lines.append(scan_thread_line(stats))
    return lines


def scan_thread_line(stats: CycleStats) -> str:
    """Where the scan thread runs: its real-time priority, the processor it keeps."""
    how = f"real-time (SCHED_FIFO {stats.priority})" if stats.priority else "normal priority"
    where = f"on processor {stats.core}, kept for it" if stats.core >= 0 else "on any processor"
    return f"scan thread: {how}, {where}"


def comm_line(stats: CycleStats) -> str:
    """The share of the cycle commands may take, and how often it ran out."""
    n = stats.comm_limited
    ran_out = (
        f"ran out at {n} scan boundar{'ies' if n != 1 else 'y'} "
        "(the commands left waited for the next)"
        if n
        else "never ran out"
    )
    share = f"up to {stats.comm_load:g} % of the cycle at each scan boundary"
    return f"communication: {share}; {ran_out}"


def _cycle_line(report: CycleReport) -> str:
    over = ", overran" if report.overrun else ""
    parts = describe_cycle(report.cycle_ms, report.parts)
    return f"cycle {report.scan} at {clock(report.at_ms)}{over}, {parts}"


def clock(ms: int | None) -> str:
    """A CPU time in ms as the local wall clock's ``HH:MM:SS`` ("" for none)."""
    return "" if ms is None else time.strftime("%H:%M:%S", time.localtime(ms / 1000))
