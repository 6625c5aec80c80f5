"""The processor kept for the scan: the scan thread on one core, everything else off it.

S7-1500 software controllers (CPU 1507S, 1508S) run the PLC on processor cores set aside
for it, the PC's other software on the rest; a soft PLC sharing every core with its own
view, bus and writer finds them on its processor when a scan falls due, and a real-time
thread on a kernel that is not fully preemptible waits for them to leave it. Measured with
200 sequencers under a command flood on 2 cores (``bench/jitter.py``): the scan thread
waited for a processor 0.46 ms per cycle on average sharing both cores, 0.11-0.14 ms with
one kept for it.

``--core`` (``CPU = {"core": ...}`` in a program) says which:

- ``auto`` (the default): the last processor this process may use, when the scan runs
  real-time and the process may use two or more; otherwise none (a scan at the normal
  priority is better off free to move to whichever processor is idle);
- a processor number: that one (real-time or not);
- ``off``: none; every thread may run anywhere.

:func:`kept_free` (the chart runner, before the bus and the view start: threads and
processes inherit it) moves the calling thread off the kept core; the runner then puts its
scan thread on it and the process's other threads on the rest while its loop runs
(``engine/runner.py``), and gives every thread the whole set back when it ends. Processes
other than s7graph's may still run there: a machine that must keep the core for the scan
alone says so to the kernel (``isolcpus=``).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["allowed_cpus", "kept_free", "others", "pin", "scan_core"]


def allowed_cpus() -> set[int]:
    """The processors this thread may run on (all of them where the system does not say)."""
    try:
        return set(os.sched_getaffinity(0))
    except (OSError, AttributeError):  # not Linux
        return set(range(os.cpu_count() or 1))


def scan_core(
    choice: str | int | None, *, realtime: bool, allowed: set[int] | None = None
) -> int | None:
    """The processor kept for the scan for ``choice`` (``auto``/None, ``off``, or a number as
    an int or a string), the scan running ``realtime`` or not, among ``allowed`` (default:
    this thread's); None: no processor kept. ValueError naming the choice and the
    processors there are for one that cannot be."""
    pool = sorted(allowed_cpus() if allowed is None else allowed)
    if choice is None or choice == "auto":
        return pool[-1] if realtime and len(pool) >= 2 else None
    if choice == "off":
        return None
    if isinstance(choice, bool) or not (
        isinstance(choice, int) or (isinstance(choice, str) and choice.isdigit())
    ):
        raise ValueError(f"core {choice!r} is none of auto, off or a processor number")
    core = int(choice)
    if core not in pool:
        there = ", ".join(map(str, pool))
        raise ValueError(f"core {core} is not a processor this process may use ({there})")
    return core


def others(core: int, allowed: set[int] | None = None) -> set[int]:
    """The processors but ``core`` (all of ``allowed`` when it is the only one)."""
    pool = allowed_cpus() if allowed is None else allowed
    return pool - {core} or set(pool)


def pin(cpus: set[int], tid: int = 0) -> bool:
    """Let thread ``tid`` (a native id; 0: the calling thread) run on ``cpus`` only; False
    when the system refuses (or the thread is gone)."""
    try:
        os.sched_setaffinity(tid, cpus)
    except (OSError, AttributeError, ValueError):
        return False
    return True


@contextmanager
def kept_free(core: int | None) -> Iterator[None]:
    """The calling thread, and so the threads and processes it starts meanwhile, off
    ``core`` (nothing for None); its processors back at the end."""
    if core is None:
        yield
        return
    before = allowed_cpus()
    moved = pin(others(core, before | {core}))
    try:
        yield
    finally:
        if moved:
            pin(before)
