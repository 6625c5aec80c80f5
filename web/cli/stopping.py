"""How a long-running command (``router``, ``web``, ``watch``) waits for its end."""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading

__all__ = ["say", "wait_until_stopped"]


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


def say(line: str, stop: threading.Event) -> None:
    """Print ``line`` for a reader that may have gone (``watch … | head -1``): then the
    command ends quietly (``stop`` set; stdout on /dev/null, so nothing more fails at
    exit), never with a traceback of a broken pipe."""
    try:
        print(line, flush=True)
    except (BrokenPipeError, ValueError):  # the pipe went, or stdout is closed already
        with contextlib.suppress(OSError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        stop.set()
