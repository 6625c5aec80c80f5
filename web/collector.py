"""The garbage collector of a process that serves the bus's edges (a view, the OPC UA face):
what the process built to start — hundreds of thousands of objects, a page's scene, an
address space — goes to the permanent generation, which no collection walks again
(CPython's ``gc.freeze``), so that a full collection walks only what came later and no
longer stops the process for long while it passes a step change on. Call it once the
process has started, in a process of its own only: the settings are the whole
interpreter's. A CPU's scan loop has its own policy (``engine.runner``: collections in the
scan's idle time)."""

from __future__ import annotations

import gc
from typing import Final

__all__ = ["GC_THRESHOLDS", "freeze_start", "quiet_collector"]

GC_THRESHOLDS: Final = (50_000, 50, 1000)
"""Allocations before a young collection (CPython's default 700), and young and middle
collections before the next older one (10, 10): :func:`quiet_collector`'s."""


def freeze_start() -> None:
    """Collect once and freeze what is left; collections go on as CPython schedules them
    (a process that drops long-lived objects — a page closed, a chart replaced — keeps
    having its full collections find their cycles)."""
    gc.collect()
    gc.freeze()


def quiet_collector() -> None:
    """:func:`freeze_start`, and the young generations collected less often and the oldest
    almost never: for a process whose objects, once built, live as long as it does."""
    freeze_start()
    gc.set_threshold(*GC_THRESHOLDS)
