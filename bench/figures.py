"""What the benchmarks share: min/median/max of repeated runs, a percentile, the opcodes
of a call, and the two helpers of the benchmarks that start a CPU with its view (a free
port, is it serving)."""

from __future__ import annotations

import socket
import statistics
import sys
import urllib.request
from collections.abc import Callable
from typing import Any

__all__ = ["free_port", "opcodes", "pct", "serves", "spread"]


def spread(values: list[float], fmt: str = "{:.2f}") -> str:
    """``min/median/max`` of repeated runs (NaNs left out; one value alone; ``-`` for none)."""
    values = [v for v in values if v == v]
    if not values:
        return "-"
    if len(values) == 1:
        return fmt.format(values[0])
    lo, mid, hi = min(values), statistics.median(values), max(values)
    return "/".join(fmt.format(v) for v in (lo, mid, hi))


def pct(values: list[float], q: float) -> float:
    """The ``q`` quantile (0..1) of ``values`` by rank, NaN for none."""
    s = sorted(values)
    return s[min(len(s) - 1, int(q * len(s)))] if s else float("nan")


def free_port() -> int:
    """A TCP port free on 127.0.0.1 now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def serves(url: str) -> bool:
    """Whether ``url`` answers 200."""
    try:
        with urllib.request.urlopen(url, timeout=5) as page:
            return bool(page.status == 200)
    except OSError:
        return False


def opcodes(run: Callable[[], object]) -> tuple[int, int]:
    """The Python opcodes and Python-level calls of one ``run()`` (``sys.settrace`` with
    opcode events): deterministic, unlike its time."""
    ops = calls = 0

    def trace(frame: Any, event: str, arg: Any) -> Any:
        nonlocal ops, calls
        if event == "call":
            frame.f_trace_opcodes = True
            calls += 1
        elif event == "opcode":
            ops += 1
        return trace

    sys.settrace(trace)
    try:
        run()
    finally:
        sys.settrace(None)
    return ops, calls
