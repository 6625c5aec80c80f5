"""How a long-running command (``router``, ``web``, ``watch``) waits for its end."""

from __future__ import annotations

import contextlib
import signal
import threading

__all__ = ["wait_until_stopped"]


def wait_until_stopped(
    duration_s: float | None = None, stop: threading.Event | None = None
) -> None:
    """Block until Ctrl-C, SIGTERM, ``duration_s`` seconds (None: no limit) or ``stop``."""
    stop = stop if stop is not None else threading.Event()
    previous = signal.signal(signal.SIGTERM, lambda *_: stop.set())
    try:
        with contextlib.suppress(KeyboardInterrupt):
            stop.wait(duration_s)
    finally:
        signal.signal(signal.SIGTERM, previous)
