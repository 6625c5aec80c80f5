"""The garbage collector of a process that serves the bus's edges (a view, the OPC UA face):
what the process built to start — hundreds of thousands of objects, a page's scene, an
address space — goes to the permanent generation, which no collection walks again, and
the young generations are collected less often, so that no full collection stops the
process for long while it passes a step change on (CPython's ``gc.freeze``,
``gc.set_threshold``). Call it once the process has started, in a process of its own only:
the settings are the whole interpreter's. A CPU's scan loop has its own policy
(``engine.runner``: collections in the scan's idle time)."""

from __future__ import annotations

import gc
from typing import Final

__all__ = ["GC_THRESHOLDS", "quiet_collector"]

GC_THRESHOLDS: Final = (50_000, 50, 1000)
"""Allocations before a young collection (CPython's default 700), and young and middle
collections before the next older one (10, 10)."""


def quiet_collector() -> None:
    """Collect once, freeze what is left, and collect the young generations less often."""
    gc.collect()
    gc.freeze()
    gc.set_threshold(*GC_THRESHOLDS)
