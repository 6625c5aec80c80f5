"""Another thread of the process, standing for the bus or the state writer, for the tests
that look at how the runner treats the threads beside its scan thread."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def bystander() -> Iterator[int]:
    """A thread that waits, alive for the block: its native id."""
    ready, done = threading.Event(), threading.Event()
    tid: list[int] = []

    def wait() -> None:
        tid.append(threading.get_native_id())
        ready.set()
        done.wait(30)

    other = threading.Thread(target=wait)
    other.start()
    try:
        ready.wait(5)
        yield tid[0]
    finally:
        done.set()
        other.join()
