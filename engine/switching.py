"""The interpreter's switch interval: how long a thread that holds Python's lock keeps it
from another thread that asks for it (5 ms by default, ``sys.getswitchinterval``)."""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterator
from typing import Final

__all__ = ["SWITCH_S", "switching"]

SWITCH_S: Final = 0.0005
"""The interval the runner's loop and the chart's loading use (the default is 5 ms)."""


@contextlib.contextmanager
def switching(interval_s: float = SWITCH_S) -> Iterator[None]:
    """The switch interval at most ``interval_s`` for the ``with`` block, then as before."""
    before = sys.getswitchinterval()
    sys.setswitchinterval(min(before, interval_s))
    try:
        yield
    finally:
        sys.setswitchinterval(before)
